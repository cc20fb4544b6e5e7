"""Cellular genetic algorithm (cGA) on a toroidal 2D grid, as an ask/tell optimizer.

Source: Alba & Dorronsoro, *Cellular Genetic Algorithms* (Springer 2008): each cell holds
one individual; the cell is one parent, its mate is chosen among its neighbours (here by
roulette, as in Zhang et al. 2014, seed 004, sec. 3.2.1), one-point crossover with
probability ``crossover_rate``, mutation, and the offspring replaces the cell if better.

Update policies (Alba & Dorronsoro 2008, sec. 2.3; Schoenauer et al.):

- ``synchronous``: every cell breeds from the old population, all replaced at once;
- ``line_sweep``: cells updated one by one in row-major order (the seed's "順序掃描");
- ``fixed_random_sweep``: one random permutation drawn once and reused every generation;
- ``new_random_sweep``: a fresh random permutation every generation;
- ``uniform_choice``: ``pop_size`` cells drawn uniformly with replacement per generation.

Asynchronous policies are executed *exactly* but vectorised: the update sequence is split
into waves, where a cell's wave is one more than the latest wave of any earlier cell of the
sequence in its (symmetric) neighbourhood. Cells in one wave never read each other, and
every cell sees all earlier updates it would see sequentially, so a wave-by-wave update is
the sequential update. One ``ask``/``tell`` pair handles one wave; ``state.generation``
counts completed sweeps (``synchronous`` has one wave per generation).

Random numbers: at the start of each generation, after the update sequence is drawn, one
call draws ``draws[5, L]`` uniforms for the ``L`` updates of the sweep, in wave order (the
order of :meth:`CellularGA._wave_plan`): row 0 the mate pick (roulette, or tournament
entrant 1), row 1 tournament entrant 2, row 2 the one-point cut, row 3 which child is kept,
row 4 the crossover test. Update ``k`` of the sweep uses column ``k`` whichever wave it falls
in, so a one-cell-at-a-time sweep consuming the same columns gives the same result. Only
the mutation (and a registry crossover other than one-point) draws per wave.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from evomotion.core.neighbourhoods import NEIGHBOURHOODS, grid_shape, neighbour_table
from evomotion.core.operators import CROSSOVERS, MUTATIONS
from evomotion.core.operators.crossover import one_point
from evomotion.core.operators.mutation import clip_to_bounds
from evomotion.core.optimizer import Optimizer, check_rates
from evomotion.core.problem import GenomeSpec
from evomotion.core.registry import lookup

UPDATE_POLICIES: tuple[str, ...] = (
    "synchronous", "line_sweep", "fixed_random_sweep", "new_random_sweep", "uniform_choice")
MATE_SELECTIONS: tuple[str, ...] = ("roulette", "tournament", "best")
REPLACEMENTS: tuple[str, ...] = ("if_better", "if_not_worse", "always")

#: ``mutate(x[n, d], rng, rate) -> x'``: a problem-supplied mutation replacing the registry one
MutateFn = Callable[[np.ndarray, np.random.Generator, float], np.ndarray]


@dataclass(frozen=True)
class CGAConfig:
    """Settings of the cellular GA (``[algorithm]`` with ``name = "cga"``)."""

    name: str = "cga"
    pop_size: int = 100
    rows: int = 0  # 0: most square grid with rows * cols == pop_size
    neighbourhood: str = "L5"
    update: str = "line_sweep"
    mate_selection: str = "roulette"
    crossover: str = "one_point"
    crossover_params: dict[str, Any] = field(default_factory=dict)
    crossover_rate: float = 1.0
    mutation: str = "uniform_reset"
    mutation_params: dict[str, Any] = field(default_factory=dict)
    mutation_rate: float = 0.1
    replacement: str = "if_better"

    def validate(self) -> None:
        grid_shape(self.pop_size, self.rows)
        check_rates(self, "crossover_rate", "mutation_rate")
        lookup(dict.fromkeys(NEIGHBOURHOODS), "neighbourhood", self.neighbourhood)
        lookup(dict.fromkeys(UPDATE_POLICIES), "update policy", self.update)
        lookup(dict.fromkeys(MATE_SELECTIONS), "mate selection", self.mate_selection)
        lookup(dict.fromkeys(REPLACEMENTS), "replacement", self.replacement)
        lookup(CROSSOVERS, "crossover", self.crossover)
        lookup(MUTATIONS, "mutation", self.mutation)


@dataclass
class CGAState:
    pop: np.ndarray
    cost: np.ndarray
    best_x: np.ndarray
    best_cost: float
    sweep_order: np.ndarray  # the fixed random sweep (drawn at init)
    sequence: np.ndarray  # cells of this generation's update sequence
    waves: np.ndarray  # wave of each sequence position
    cells: np.ndarray  # cells whose offspring were asked last
    generation: int = 0
    wave: int = 0
    evaluated: bool = False
    #: this generation's uniforms, ``[5, len(sequence)]`` in wave order (see module doc)
    draws: np.ndarray = field(default_factory=lambda: np.empty((5, 0)))


def update_waves(sequence: np.ndarray, table: np.ndarray) -> np.ndarray:
    """Wave index of each position of ``sequence`` (sequential semantics, see module doc)."""
    last = np.full(table.shape[0], -1, dtype=np.int64)
    waves = np.empty(len(sequence), dtype=np.int64)
    for k, c in enumerate(sequence.tolist()):
        w = int(last[table[c]].max()) + 1
        waves[k] = w
        last[c] = w
    return waves


def roulette_rows(cost: np.ndarray, rng: np.random.Generator | None,
                  u: np.ndarray | None = None) -> np.ndarray:
    """Column index per row by fitness-proportional selection on minimised ``cost[n, k]``.

    Weights per row are ``worst - cost + 1e-3 * spread`` (uniform when the row is flat);
    ``inf`` costs get weight 0 unless the whole row is ``inf``. ``u[n, 1]``: uniforms in
    [0, 1) to use instead of drawing them from ``rng``.
    """
    if u is None:
        u = rng.random((cost.shape[0], 1))
    finite = np.isfinite(cost)
    if finite.all():  # the same weights without the inf handling
        hi, lo = cost.max(1, keepdims=True), cost.min(1, keepdims=True)
        spread = hi - lo
        w = hi - cost + np.where(spread > 0, 1e-3 * spread, 1.0)
        cdf = np.cumsum(w, axis=1)
        return np.minimum((cdf <= u * cdf[:, -1:]).sum(1), cost.shape[1] - 1)
    any_f = finite.any(1, keepdims=True)
    c = np.where(finite, cost, 0.0)
    hi = np.where(any_f, np.where(finite, cost, -np.inf).max(1, keepdims=True), 0.0)
    lo = np.where(any_f, np.where(finite, cost, np.inf).min(1, keepdims=True), 0.0)
    spread = hi - lo
    w = np.where(finite, hi - c + np.where(spread > 0, 1e-3 * spread, 1.0), 0.0)
    w[~any_f[:, 0]] = 1.0
    cdf = np.cumsum(w, axis=1)
    return np.minimum((cdf <= u * cdf[:, -1:]).sum(1), cost.shape[1] - 1)


def one_point_masks(draws: np.ndarray, dim: int, crossover_rate: float) -> np.ndarray:
    """``take_mate[L, dim]``: where the kept child of the fused one-point crossover takes
    the mate's gene, from ``draws`` rows 2-4 (cut in 1..dim-1, child, crossover test):
    child 0 takes the mate's tail, child 1 its head; no crossover keeps the cell."""
    cut = 1 + (draws[2] * (dim - 1)).astype(np.int64)
    keep_head = draws[3] >= 0.5  # child 1
    cross = draws[4] < crossover_rate
    return ((np.arange(dim) >= cut[:, None]) != keep_head[:, None]) & cross[:, None]


class CellularGA(Optimizer):
    """Cellular GA; ``cfg`` is a :class:`CGAConfig`; ``mutate`` overrides the mutation."""

    name = "cga"

    def __init__(self, genome: GenomeSpec, cfg: CGAConfig, mutate: MutateFn | None = None):
        super().__init__(genome)
        cfg.validate()
        self.cfg = cfg
        self.rows, self.cols = grid_shape(cfg.pop_size, cfg.rows)
        self._xo = CROSSOVERS[cfg.crossover]
        self._mutate = mutate
        self._tables: dict[int, np.ndarray] = {}
        self._waves: dict[int, np.ndarray] = {}
        self._plans: dict[int, list[tuple[np.ndarray, ...]]] = {}  # fixed sweeps
        self._plan: list[tuple[np.ndarray, ...]] = []  # (cells, neighbours, rows) per wave
        self._plan_of: CGAState | None = None  # the state whose schedule ``_plan`` holds
        self._fast_one_point = self._xo is one_point and not cfg.crossover_params
        self._masks: tuple[np.ndarray, np.ndarray] | None = None  # (draws, one_point_masks)

    def table(self, generation: int) -> np.ndarray:
        key = generation % 2 if self.cfg.neighbourhood == "Margolus" else 0
        if key not in self._tables:
            self._tables[key] = neighbour_table(self.cfg.neighbourhood, self.rows, self.cols, key)
        return self._tables[key]

    def init(self, rng: np.random.Generator, pop: np.ndarray | None = None) -> CGAState:
        n, d = self.cfg.pop_size, self.genome.dim
        pop = self.genome.sample(rng, n) if pop is None else np.array(pop, dtype=float)
        if pop.shape != (n, d):
            raise ValueError(f"cga: initial population has shape {pop.shape}, want {(n, d)}")
        empty = np.empty(0, dtype=np.int64)
        return CGAState(pop=pop, cost=np.full(n, np.inf), best_x=np.full(d, np.nan),
                        best_cost=np.inf, sweep_order=rng.permutation(n), sequence=empty,
                        waves=empty, cells=empty)

    def _schedule(self, state: CGAState, rng: np.random.Generator) -> None:
        n, pol = self.cfg.pop_size, self.cfg.update
        table = self.table(state.generation)
        if pol == "synchronous":
            state.sequence, state.waves = np.arange(n), np.zeros(n, dtype=np.int64)
            return
        seq = {"line_sweep": np.arange(n), "fixed_random_sweep": state.sweep_order,
               "new_random_sweep": rng.permutation(n) if pol == "new_random_sweep" else None,
               "uniform_choice": rng.integers(0, n, n) if pol == "uniform_choice" else None}[pol]
        key = state.generation % 2 if self.cfg.neighbourhood == "Margolus" else 0
        if pol in ("line_sweep", "fixed_random_sweep"):
            if key not in self._waves:
                self._waves[key] = update_waves(seq, table)
            waves = self._waves[key]
        else:
            waves = update_waves(seq, table)
        state.sequence, state.waves = np.asarray(seq), waves

    def _wave_plan(self, state: CGAState) -> list[tuple[Any, ...]]:
        """``(cells, neighbours, arange(len(cells)), slice of the sweep)`` of every wave of
        the current schedule, split once per schedule (kept across generations for the line
        and fixed sweeps)."""
        if self._plan_of is state:
            return self._plan
        fixed = self.cfg.update in ("line_sweep", "fixed_random_sweep", "synchronous")
        key = state.generation % 2 if self.cfg.neighbourhood == "Margolus" else 0
        if not (fixed and key in self._plans):
            order = np.argsort(state.waves, kind="stable")  # sequence order within a wave
            ends = np.cumsum(np.bincount(state.waves))[:-1]
            table = self.table(state.generation)
            bounds = np.r_[0, ends, len(order)].tolist()
            plan = [(c, table[c, 1:], np.arange(len(c)), slice(lo, hi))
                    for c, lo, hi in zip(np.split(state.sequence[order], ends), bounds[:-1],
                                         bounds[1:], strict=True)]
            if not fixed:
                self._plan, self._plan_of = plan, state
                return plan
            self._plans[key] = plan
        self._plan, self._plan_of = self._plans[key], state
        return self._plan

    def _ask(self, state: CGAState, rng: np.random.Generator):
        if not state.evaluated:
            return state.pop.copy(), state
        if state.wave == 0:
            self._schedule(state, rng)
            self._plan_of = None
            state.draws = rng.random((5, len(state.sequence)))
        c, g = self.cfg, self.genome
        cells, nbr, rows, part = self._wave_plan(state)[state.wave]
        u = state.draws[:, part]
        ncost = state.cost[nbr]
        if c.mate_selection == "roulette":
            j = roulette_rows(ncost, None, u[0, :, None])
        elif c.mate_selection == "tournament":
            a, b = (u[:2] * nbr.shape[1]).astype(np.int64)
            j = np.where(ncost[rows, a] <= ncost[rows, b], a, b)
        else:
            j = np.argmin(ncost, axis=1)
        mates = nbr[rows, j]
        a, b = state.pop[cells], state.pop[mates]
        if self._fast_one_point and g.dim >= 2:
            # one_point fused with the pick of a child and the crossover test; the masks of
            # the whole sweep are built once per generation
            if self._masks is None or self._masks[0] is not state.draws:
                self._masks = (state.draws, one_point_masks(state.draws, g.dim,
                                                            c.crossover_rate))
            child = np.where(self._masks[1][part], b, a)
        else:
            kids = self._xo(a, b, rng, **c.crossover_params)
            child = np.where(u[3, :, None] < 0.5, kids[0], kids[1])
            child = np.where(u[4, :, None] < c.crossover_rate, child, a)
        if self._mutate is not None:
            child = self._mutate(child, rng, c.mutation_rate)
        else:
            child = MUTATIONS[c.mutation](child, g.lower, g.upper, rng, c.mutation_rate,
                                          **c.mutation_params)
        state.cells = cells
        return clip_to_bounds(child, g.lower, g.upper), state

    def _tell(self, state: CGAState, genomes, cost, rng):
        if not state.evaluated:
            state.pop, state.cost, state.evaluated = genomes.copy(), cost.copy(), True
            i = int(np.argmin(state.cost))
            if state.cost[i] < state.best_cost:
                state.best_cost, state.best_x = float(state.cost[i]), state.pop[i].copy()
            return state
        cells, old = state.cells, state.cost[state.cells]
        rep = self.cfg.replacement
        better = (cost < old if rep == "if_better" else cost <= old if rep == "if_not_worse"
                  else np.ones(len(cells), bool))
        if better.any():
            won, x, f = cells[better], genomes[better], cost[better]
            state.pop[won], state.cost[won] = x, f
            i = int(np.argmin(f))  # only new entries can beat the best seen so far
            if f[i] < state.best_cost:
                state.best_cost, state.best_x = float(f[i]), x[i].copy()
        state.wave += 1
        if state.wave >= len(self._wave_plan(state)):
            state.wave, state.generation = 0, state.generation + 1
        return state

    def best(self, state: CGAState):
        return state.best_x, state.best_cost

    def end_of_generation(self, state: CGAState) -> bool:
        """True right after the last wave of a generation (or the initial evaluation)."""
        return state.evaluated and state.wave == 0


def make_cga(genome: GenomeSpec, cfg: CGAConfig, mutate: MutateFn | None = None) -> CellularGA:
    """Factory for the ``ALGORITHMS`` registry (``"cga"``)."""
    return CellularGA(genome, cfg, mutate)
