"""Generational genetic algorithm assembled from the operator registries.

A real-coded GA in the form of Goldberg (1989) / Eiben & Smith (2015, ch. 3-5): parent
selection, pairwise crossover with probability ``crossover_rate``, mutation, bound repair
by clipping, and survivor selection (generational with elites, or (mu+lambda)). This is the
GA of seeds 000 (BLX-alpha, roulette, elitism 0.1) and 004 (panmictic baseline).

Wright's linear crossover yields three children per pair; all three are evaluated and
``tell`` keeps the best two of each triple before replacement (Wright 1991).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from evomotion.core.operators import CROSSOVERS, MUTATIONS, REPLACEMENTS, SELECTIONS
from evomotion.core.operators.mutation import clip_to_bounds
from evomotion.core.optimizer import Optimizer, check_rates
from evomotion.core.problem import GenomeSpec
from evomotion.core.registry import lookup


@dataclass(frozen=True)
class GAConfig:
    """Settings of the generational GA (the ``[algorithm]`` section with ``name = "ga"``)."""

    name: str = "ga"
    pop_size: int = 100
    crossover: str = "blx_alpha"
    crossover_params: dict[str, Any] = field(default_factory=dict)
    crossover_rate: float = 0.9
    mutation: str = "gaussian"
    mutation_params: dict[str, Any] = field(default_factory=dict)
    mutation_rate: float = 0.3
    selection: str = "tournament"
    selection_params: dict[str, Any] = field(default_factory=dict)
    elitism: float = 0.1
    replacement: str = "generational"

    def validate(self) -> None:
        if self.pop_size < 2:
            raise ValueError(f"algorithm.pop_size must be >= 2, got {self.pop_size}")
        check_rates(self, "crossover_rate", "mutation_rate")
        if self.elitism < 0 or (self.elitism >= 1 and self.elitism > self.pop_size):
            raise ValueError(f"algorithm.elitism must be a fraction in [0, 1) or a count "
                             f"<= pop_size, got {self.elitism}")
        lookup(CROSSOVERS, "crossover", self.crossover)
        lookup(MUTATIONS, "mutation", self.mutation)
        lookup(SELECTIONS, "selection", self.selection)
        lookup(REPLACEMENTS, "replacement", self.replacement)

    @property
    def n_elite(self) -> int:
        e = self.elitism
        return int(round(e * self.pop_size)) if e < 1 else int(e)


@dataclass
class GAState:
    pop: np.ndarray
    cost: np.ndarray
    best_x: np.ndarray
    best_cost: float
    generation: int = 0
    evaluated: bool = False


class GA(Optimizer):
    """Generational GA; ``cfg`` is a :class:`GAConfig`."""

    name = "ga"

    def __init__(self, genome: GenomeSpec, cfg: GAConfig) -> None:
        super().__init__(genome)
        cfg.validate()
        self.cfg = cfg
        self._xo = CROSSOVERS[cfg.crossover]
        self._mut = MUTATIONS[cfg.mutation]
        self._sel = SELECTIONS[cfg.selection]
        self._rep = REPLACEMENTS[cfg.replacement]
        self._k = 3 if cfg.crossover == "linear" else 2

    @property
    def n_offspring(self) -> int:
        c = self.cfg
        return c.pop_size - c.n_elite if c.replacement == "generational" else c.pop_size

    def init(self, rng: np.random.Generator, pop: np.ndarray | None = None) -> GAState:
        d = self.genome.dim
        if pop is None:
            pop = self.genome.sample(rng, self.cfg.pop_size)
        return GAState(pop=np.asarray(pop, float), cost=np.full(len(pop), np.inf),
                       best_x=np.full(d, np.nan), best_cost=np.inf)

    def _ask(self, state: GAState, rng: np.random.Generator):
        if not state.evaluated:
            return state.pop.copy(), state
        c, g = self.cfg, self.genome
        n_pairs = math.ceil(self.n_offspring / 2)
        idx = self._sel(state.cost, 2 * n_pairs, rng, **c.selection_params)
        a, b = state.pop[idx[:n_pairs]], state.pop[idx[n_pairs:]]
        kids = self._xo(a, b, rng, **c.crossover_params)  # [k, n_pairs, d]
        keep = rng.random(n_pairs) >= c.crossover_rate
        if keep.any():
            kids[0, keep], kids[1, keep] = a[keep], b[keep]
            if self._k == 3:
                kids[2, keep] = a[keep]
        flat = kids.transpose(1, 0, 2).reshape(-1, g.dim)  # pair-major
        flat = self._mut(flat, g.lower, g.upper, rng, c.mutation_rate, **c.mutation_params)
        flat = clip_to_bounds(flat, g.lower, g.upper, out=flat)
        if self._k == 2:
            flat = flat[: self.n_offspring]
        return flat, state

    def _tell(self, state: GAState, genomes, cost, rng):
        if not state.evaluated:
            state.cost = cost.copy()
            state.pop = genomes.copy()
            state.evaluated = True
        else:
            kids, kcost = genomes, cost
            if self._k == 3:
                kids, kcost = _best_two_of_three(kids, kcost, self.n_offspring)
            state.pop, state.cost = self._rep(state.pop, state.cost, kids, kcost,
                                              self.cfg.n_elite)
            state.generation += 1
        i = int(np.argmin(state.cost))
        if state.cost[i] < state.best_cost:
            state.best_cost, state.best_x = float(state.cost[i]), state.pop[i].copy()
        return state

    def best(self, state: GAState):
        return state.best_x, state.best_cost


def _best_two_of_three(kids: np.ndarray, cost: np.ndarray, n: int):
    """Keep the two lowest-cost children of each consecutive triple, then the first ``n``."""
    d = kids.shape[1]
    k3 = kids.reshape(-1, 3, d)
    c3 = cost.reshape(-1, 3)
    order = np.argsort(c3, axis=1, kind="stable")[:, :2]
    rows = np.arange(k3.shape[0])[:, None]
    return k3[rows, order].reshape(-1, d)[:n], c3[rows, order].reshape(-1)[:n]
