"""Generational genetic algorithm assembled from the operator registries.

A real-coded GA in the form of Goldberg (1989) / Eiben & Smith (2015, ch. 3-5): parent
selection, pairwise crossover with probability ``crossover_rate``, mutation, bound repair
by clipping, and survivor selection (generational with elites, or (mu+lambda)). This is the
GA of papers 000 (BLX-alpha, roulette, elitism 0.1) and 004 (panmictic baseline).

Wright's linear crossover yields three children per pair; all three are evaluated and
``tell`` keeps the best two of each triple before replacement (Wright 1991).

A problem mutation ``mutate(x, rng, rate)`` (``GA(genome, cfg, mutate=m)``) replaces the
registry mutation: the registry mutation still runs, at rate 0 (it draws its random numbers
but changes nothing), then the children are clipped into the box and ``m(children, rng,
cfg.mutation_rate)`` is applied to them. This is, random stream included, the grid-path
study's former outer loop (a GA built with ``mutation_rate=0`` whose asked children were
mutated by the path mutation). ``init(rng, population)`` starts from the given
``[pop_size, d]`` population instead of a uniform sample. State is replaced, never mutated.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from evomotion.core.checks import MAX_POP_SIZE, check_fields, check_number
from evomotion.core.operators import CROSSOVERS, MUTATIONS, REPLACEMENTS, SELECTIONS
from evomotion.core.operators.mutation import clip_to_bounds
from evomotion.core.operators.params import check_genome_params, check_operator_params
from evomotion.core.optimizer import MutateFn, Optimizer, check_rates
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
        """One-line errors for impossible settings, operator parameters included (their
        keys against the operator's signature, their values against its range)."""
        check_fields(self, "algorithm")
        if self.pop_size < 2:
            raise ValueError(f"algorithm.pop_size must be >= 2, got {self.pop_size}")
        check_number("algorithm.pop_size", self.pop_size, hi=MAX_POP_SIZE, integer=True)
        check_rates(self, "crossover_rate", "mutation_rate")
        if self.elitism < 0 or (self.elitism >= 1 and self.elitism > self.pop_size):
            raise ValueError(f"algorithm.elitism must be a fraction in [0, 1) or a count "
                             f"<= pop_size, got {self.elitism}")
        check_operator_params("algorithm.crossover_params", "crossover", self.crossover,
                              lookup(CROSSOVERS, "crossover", self.crossover),
                              self.crossover_params)
        check_operator_params("algorithm.mutation_params", "mutation", self.mutation,
                              lookup(MUTATIONS, "mutation", self.mutation), self.mutation_params)
        check_operator_params("algorithm.selection_params", "selection", self.selection,
                              lookup(SELECTIONS, "selection", self.selection),
                              self.selection_params, limits={"k": {"hi": self.pop_size}})
        lookup(REPLACEMENTS, "replacement", self.replacement)

    @property
    def n_elite(self) -> int:
        e = self.elitism
        return int(round(e * self.pop_size)) if e < 1 else int(e)


@dataclass
class GAState:
    pop: np.ndarray  # current population [pop_size, d]
    cost: np.ndarray  # its costs (inf before the first tell)
    best_x: np.ndarray
    best_cost: float
    generation: int = 0  # completed generations, the initial evaluation included
    evaluated: bool = False  # the initial population has been told


class GA(Optimizer):
    """Generational GA; ``cfg`` is a :class:`GAConfig`; ``mutate`` replaces the registry
    mutation (see the module doc)."""

    name = "ga"

    def __init__(self, genome: GenomeSpec, cfg: GAConfig, *,
                 mutate: MutateFn | None = None) -> None:
        super().__init__(genome, mutate=mutate)
        cfg.validate()
        check_genome_params(cfg, genome)
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

    def init(self, rng: np.random.Generator, population: np.ndarray | None = None) -> GAState:
        n, d = self.cfg.pop_size, self.genome.dim
        if population is None:
            pop = self.genome.sample(rng, n)
        else:
            pop = np.array(population, dtype=float)
            if pop.shape != (n, d):
                raise ValueError(f"ga: initial population has shape {pop.shape}, want {(n, d)}")
        return GAState(pop=pop, cost=np.full(n, np.inf), best_x=np.full(d, np.nan),
                       best_cost=np.inf)

    def _ask(self, state: GAState, rng: np.random.Generator):
        if not state.evaluated:
            return state.pop.copy(), state
        c, g = self.cfg, self.genome
        n_pairs = math.ceil(self.n_offspring / 2)
        idx = self._sel(state.cost, 2 * n_pairs, rng, **c.selection_params)
        a, b = state.pop[idx[:n_pairs]], state.pop[idx[n_pairs:]]
        kids = self._xo(a, b, rng, **c.crossover_params)  # [k, n_pairs, d], a new array
        keep = rng.random(n_pairs) >= c.crossover_rate
        if keep.any():
            kids[0, keep], kids[1, keep] = a[keep], b[keep]
            if self._k == 3:
                kids[2, keep] = a[keep]
        flat = kids.transpose(1, 0, 2).reshape(-1, g.dim)  # pair-major
        rate = 0.0 if self.mutate is not None else c.mutation_rate
        flat = self._mut(flat, g.lower, g.upper, rng, rate, **c.mutation_params)
        flat = clip_to_bounds(flat, g.lower, g.upper, out=flat)
        if self._k == 2:
            flat = flat[: self.n_offspring]
        if self.mutate is not None:
            flat = self.mutate(flat, rng, c.mutation_rate)
        return flat, state

    def _tell(self, state: GAState, genomes, cost, rng, measures=None):
        if not state.evaluated:
            return replace(state, pop=np.array(genomes, dtype=float), cost=cost.copy(),
                           evaluated=True)
        kids, kcost = genomes, cost
        if self._k == 3:
            kids, kcost = _best_two_of_three(kids, kcost, self.n_offspring)
        pop, pcost = self._rep(state.pop, state.cost, kids, kcost, self.cfg.n_elite)
        return replace(state, pop=pop, cost=pcost)


def make_ga(genome: GenomeSpec, cfg: GAConfig, *, mutate: MutateFn | None = None) -> GA:
    """Factory for the ``ALGORITHMS`` registry (``"ga"``)."""
    return GA(genome, cfg, mutate=mutate)


def _best_two_of_three(kids: np.ndarray, cost: np.ndarray, n: int):
    """Keep the two lowest-cost children of each consecutive triple, then the first ``n``."""
    d = kids.shape[1]
    k3 = kids.reshape(-1, 3, d)
    c3 = cost.reshape(-1, 3)
    order = np.argsort(c3, axis=1, kind="stable")[:, :2]
    rows = np.arange(k3.shape[0])[:, None]
    return k3[rows, order].reshape(-1, d)[:n], c3[rows, order].reshape(-1)[:n]
