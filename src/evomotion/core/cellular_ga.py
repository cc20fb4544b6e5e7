"""Cellular genetic algorithm (cGA) on a toroidal 2D grid, as an ask/tell optimizer.

Source: Alba & Dorronsoro, *Cellular Genetic Algorithms* (Springer 2008): each cell holds
one individual; the cell is one parent, its mate is chosen among its neighbours (here by
roulette, as in Zhang et al. 2014, paper 004, sec. 3.2.1), one-point crossover with
probability ``crossover_rate``, mutation, and the offspring replaces the cell if better.

Update policies (Alba & Dorronsoro 2008, sec. 2.3; Schoenauer et al.):

- ``synchronous``: every cell breeds from the old population, all replaced at once;
- ``line_sweep``: cells updated one by one in row-major order (the paper's "順序掃描");
- ``fixed_random_sweep``: one random permutation drawn once and reused every generation;
- ``new_random_sweep``: a fresh random permutation every generation;
- ``uniform_choice``: ``pop_size`` cells drawn uniformly with replacement per generation.

Asynchronous policies are executed *exactly* but vectorised: the update sequence is split
into waves, where a cell's wave is one more than the latest wave of any earlier cell of the
sequence in its (symmetric) neighbourhood. Cells in one wave never read each other, and
every cell sees all earlier updates it would see sequentially, so a wave-by-wave update is
the sequential update. One ``ask``/``tell`` pair handles one wave; a generation is one
whole sweep (``synchronous`` has one wave per generation), so :meth:`CellularGA.generation_done`
is true only after the last wave of a sweep (and after the initial evaluation), and
``state.generation - 1`` is the number of completed sweeps (it picks the Margolus parity).

State and caches: the optimizer object holds only frozen settings (the config, the grid and
its neighbour tables, pure functions of the config). What depends on the run lives in the
state and is replaced, never mutated: the fixed random sweep and the waves of the fixed sweeps
(``line_sweep``, ``fixed_random_sweep``), computed once in ``init``; and per generation the
update sequence, its waves, the sequence in wave order with the start of each wave, and the
uniforms of the sweep.

Random numbers: at the start of each generation, after the update sequence is drawn, one
call draws ``draws[5, L]`` uniforms for the ``L`` updates of the sweep, in wave order (the
order of ``state.wave_cells``): row 0 the mate pick (roulette, or tournament
entrant 1), row 1 tournament entrant 2, row 2 the one-point cut, row 3 which child is kept,
row 4 the crossover test. Update ``k`` of the sweep uses column ``k`` whichever wave it falls
in, so a one-cell-at-a-time sweep consuming the same columns gives the same result. Only
the mutation (and a registry crossover other than one-point) draws per wave.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from evomotion.core.checks import MAX_POP_SIZE, check_fields, check_number
from evomotion.core.neighbourhoods import NEIGHBOURHOODS, grid_shape, neighbour_table
from evomotion.core.operators import CROSSOVERS, MUTATIONS
from evomotion.core.operators.crossover import one_point
from evomotion.core.operators.mutation import clip_to_bounds
from evomotion.core.operators.params import check_genome_params, check_operator_params
from evomotion.core.optimizer import MutateFn, Optimizer, check_rates
from evomotion.core.problem import GenomeSpec
from evomotion.core.registry import lookup
from evomotion.core.state import replaced as replace
from evomotion.errors import InputError

UPDATE_POLICIES: tuple[str, ...] = (
    "synchronous", "line_sweep", "fixed_random_sweep", "new_random_sweep", "uniform_choice")
MATE_SELECTIONS: tuple[str, ...] = ("roulette", "tournament", "best")
REPLACEMENTS: tuple[str, ...] = ("if_better", "if_not_worse", "always")

__all__ = ["CGAConfig", "CGAState", "CellularGA", "MutateFn", "make_cga", "one_point_masks",
           "roulette_rows", "update_waves"]


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
        """One-line errors for impossible settings, operator parameters included."""
        check_fields(self, "algorithm")
        check_number("algorithm.pop_size", self.pop_size, lo=1, hi=MAX_POP_SIZE, integer=True)
        check_number("algorithm.rows", self.rows, lo=0, hi=self.pop_size, integer=True)
        rows, cols = grid_shape(self.pop_size, self.rows)
        check_rates(self, "crossover_rate", "mutation_rate")
        lookup(dict.fromkeys(NEIGHBOURHOODS), "neighbourhood", self.neighbourhood)
        if self.neighbourhood == "Margolus" and (rows < 2 or cols < 2):
            raise InputError(f"algorithm.neighbourhood: Margolus needs a grid of at least "
                             f"2x2, got {rows}x{cols} (pop_size {self.pop_size})")
        lookup(dict.fromkeys(UPDATE_POLICIES), "update policy", self.update)
        lookup(dict.fromkeys(MATE_SELECTIONS), "mate selection", self.mate_selection)
        lookup(dict.fromkeys(REPLACEMENTS), "replacement", self.replacement)
        check_operator_params("algorithm.crossover_params", "crossover", self.crossover,
                              lookup(CROSSOVERS, "crossover", self.crossover),
                              self.crossover_params)
        check_operator_params("algorithm.mutation_params", "mutation", self.mutation,
                              lookup(MUTATIONS, "mutation", self.mutation), self.mutation_params)


@dataclass
class CGAState:
    pop: np.ndarray  # one individual per cell [pop_size, d]
    cost: np.ndarray
    best_x: np.ndarray
    best_cost: float
    sweep_order: np.ndarray  # the fixed random sweep (drawn at init)
    #: ``[parities, pop_size]``: wave of each position of the fixed sweep (line and fixed
    #: random sweeps; one row per Margolus parity), empty for the other policies
    fixed_waves: np.ndarray
    sequence: np.ndarray  # cells of this generation's update sequence
    waves: np.ndarray  # wave of each sequence position
    wave_cells: np.ndarray  # the sequence in wave order (stable within a wave)
    wave_starts: np.ndarray  # start of each wave in ``wave_cells``, then its length
    generation: int = 0  # completed generations (sweeps), the initial evaluation included
    wave: int = 0  # the wave asked next (or last asked, until its tell)
    evaluated: bool = False
    #: this generation's uniforms, ``[5, len(sequence)]`` in wave order (see module doc)
    draws: np.ndarray = field(default_factory=lambda: np.empty((5, 0)))
    #: neighbours (without the cell itself) of the sweep's cells, in wave order
    wave_nbr: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), np.int64))
    #: the sweep's one-point masks ``[L, dim]`` (True: the mate's gene), from ``draws``
    masks: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), bool))


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
        if rng is None:
            raise ValueError("roulette_rows needs rng or u")
        u = rng.random((cost.shape[0], 1))
    # ufunc reductions: the same values as the ndarray methods without their Python
    # wrappers (this runs once per wave of a cellular-GA sweep)
    hi = np.maximum.reduce(cost, axis=1, keepdims=True)
    lo = np.minimum.reduce(cost, axis=1, keepdims=True)
    # finite sums iff every cost is finite (a finite sum that overflows takes the exact path)
    if math.isfinite(np.add.reduce(hi, axis=None)) and \
            math.isfinite(np.add.reduce(lo, axis=None)):  # finite costs: no inf handling
        spread = hi - lo
        w = hi - cost + np.where(spread > 0, 1e-3 * spread, 1.0)
        cdf = np.add.accumulate(w, axis=1)
        return np.minimum(np.add.reduce(cdf <= u * cdf[:, -1:], axis=1), cost.shape[1] - 1)
    finite = np.isfinite(cost)
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

    def __init__(self, genome: GenomeSpec, cfg: CGAConfig, *,
                 mutate: MutateFn | None = None) -> None:
        super().__init__(genome, mutate=mutate)
        cfg.validate()
        check_genome_params(cfg, genome)
        self.cfg = cfg
        self.rows, self.cols = grid_shape(cfg.pop_size, cfg.rows)
        self._xo = CROSSOVERS[cfg.crossover]
        self._fast_one_point = self._xo is one_point and not cfg.crossover_params
        self._rows = np.arange(cfg.pop_size)  # row numbers of a wave (a slice of it)
        parities = 2 if cfg.neighbourhood == "Margolus" else 1
        self._tables = tuple(neighbour_table(cfg.neighbourhood, self.rows, self.cols, p)
                             for p in range(parities))
        # the schedules of ``synchronous`` and ``line_sweep`` are pure functions of the
        # config too: (sequence, waves, cells in wave order, wave starts, their neighbours)
        # per parity, built once
        self._plans: tuple[tuple[np.ndarray, ...], ...] = ()
        if cfg.update in ("synchronous", "line_sweep"):
            n = cfg.pop_size
            seq = np.arange(n)
            self._plans = tuple(
                self._plan(seq, np.zeros(n, dtype=np.int64) if cfg.update == "synchronous"
                           else update_waves(seq, t), t) for t in self._tables)

    @staticmethod
    def _plan(seq: np.ndarray, waves: np.ndarray, table: np.ndarray) -> tuple[np.ndarray, ...]:
        order = np.argsort(waves, kind="stable")  # sequence order within a wave
        starts = np.r_[0, np.cumsum(np.bincount(waves))]
        cells = seq[order]
        return seq, waves, cells, starts, table[cells, 1:]

    def table(self, sweep: int) -> np.ndarray:
        """Neighbour table of sweep number ``sweep`` (0: the first sweep after the initial
        evaluation; only the Margolus table depends on it, by parity)."""
        return self._tables[sweep % len(self._tables)]

    def init(self, rng: np.random.Generator, population: np.ndarray | None = None) -> CGAState:
        n, d = self.cfg.pop_size, self.genome.dim
        pop = self.genome.sample(rng, n) if population is None else np.array(population,
                                                                             dtype=float)
        if pop.shape != (n, d):
            raise ValueError(f"cga: initial population has shape {pop.shape}, want {(n, d)}")
        sweep_order = rng.permutation(n)
        fixed = {"line_sweep": np.arange(n), "fixed_random_sweep": sweep_order}.get(
            self.cfg.update)
        if fixed is None:
            fixed_waves = np.empty((0, n), dtype=np.int64)
        else:
            fixed_waves = np.stack([update_waves(fixed, t) for t in self._tables])
        empty = np.empty(0, dtype=np.int64)
        return CGAState(pop=pop, cost=np.full(n, np.inf), best_x=np.full(d, np.nan),
                        best_cost=np.inf, sweep_order=sweep_order, fixed_waves=fixed_waves,
                        sequence=empty, waves=empty, wave_cells=empty, wave_starts=empty)

    def _schedule(self, state: CGAState, rng: np.random.Generator) -> CGAState:
        """The state with this sweep's update sequence, its waves and its uniforms."""
        n, pol = self.cfg.pop_size, self.cfg.update
        sweep = state.generation - 1
        if self._plans:  # synchronous, line_sweep
            seq, waves, cells, starts, nbr = self._plans[sweep % len(self._plans)]
        else:
            if pol == "fixed_random_sweep":
                seq, waves = state.sweep_order, state.fixed_waves[sweep % len(state.fixed_waves)]
            else:
                seq = rng.permutation(n) if pol == "new_random_sweep" else rng.integers(0, n, n)
                waves = update_waves(seq, self.table(sweep))
            seq, waves, cells, starts, nbr = self._plan(np.asarray(seq), waves,
                                                        self.table(sweep))
        draws = rng.random((5, len(seq)))
        masks = one_point_masks(draws, self.genome.dim, self.cfg.crossover_rate) \
            if self._fast_one_point and self.genome.dim >= 2 else state.masks
        return replace(state, sequence=seq, waves=waves, wave_cells=cells, wave_starts=starts,
                       draws=draws, masks=masks, wave_nbr=nbr)

    def _wave(self, state: CGAState) -> tuple[np.ndarray, slice]:
        """Cells of the current wave and their columns (slice of the sweep, wave order)."""
        lo, hi = state.wave_starts[state.wave:state.wave + 2].tolist()
        return state.wave_cells[lo:hi], slice(lo, hi)

    def _ask(self, state: CGAState, rng: np.random.Generator):
        if not state.evaluated:
            return state.pop.copy(), state
        if state.wave == 0:
            state = self._schedule(state, rng)
        c, g = self.cfg, self.genome
        cells, part = self._wave(state)
        nbr = state.wave_nbr[part]
        rows = self._rows[:len(cells)]
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
            # one_point fused with the pick of a child and the crossover test
            child = np.where(state.masks[part], b, a)
        else:
            kids = self._xo(a, b, rng, **c.crossover_params)
            child = np.where(u[3, :, None] < 0.5, kids[0], kids[1])
            child = np.where(u[4, :, None] < c.crossover_rate, child, a)
        if self.mutate is not None:
            child = self.mutate(child, rng, c.mutation_rate)
        else:
            child = MUTATIONS[c.mutation](child, g.lower, g.upper, rng, c.mutation_rate,
                                          **c.mutation_params)
        return clip_to_bounds(child, g.lower, g.upper), state

    def _tell(self, state: CGAState, genomes, cost, rng, measures=None):
        if not state.evaluated:
            return replace(state, pop=np.array(genomes, dtype=float), cost=cost.copy(),
                           evaluated=True)
        cells, _ = self._wave(state)
        if len(genomes) != len(cells):
            raise ValueError(f"cga: tell got {len(genomes)} genomes for a wave of {len(cells)}")
        old = state.cost[cells]
        rep = self.cfg.replacement
        better = (cost < old if rep == "if_better" else cost <= old if rep == "if_not_worse"
                  else np.ones(len(cells), bool))
        pop, pcost = state.pop, state.cost
        won = cells[better]
        if won.size:
            pop, pcost = pop.copy(), pcost.copy()
            pop[won], pcost[won] = genomes[better], cost[better]
        wave = state.wave + 1
        return replace(state, pop=pop, cost=pcost,
                       wave=0 if wave >= len(state.wave_starts) - 1 else wave)

    def generation_done(self, state: CGAState) -> bool:
        """True right after the last wave of a sweep (or the initial evaluation)."""
        return state.evaluated and state.wave == 0


def make_cga(genome: GenomeSpec, cfg: CGAConfig, *,
             mutate: MutateFn | None = None) -> CellularGA:
    """Factory for the ``ALGORITHMS`` registry (``"cga"``)."""
    return CellularGA(genome, cfg, mutate=mutate)
