"""MAP-Elites with Gaussian or Iso+LineDD variation, on a grid or CVT archive.

Sources: J.-B. Mouret and J. Clune, "Illuminating search spaces by mapping elites",
arXiv:1504.04909 (2015), Alg. 1: after ``initial`` random genomes, every generation selects
``pop_size`` elites uniformly from the filled cells, varies them, evaluates them and inserts
each where its cell is empty or it beats the elite. V. Vassiliades and J.-B. Mouret,
"Discovering the Elite Hypervolume by Leveraging Interspecies Correlation", GECCO 2018, eq. 1
(Iso+LineDD): ``x' = x_i + sigma_iso N(0, I) + sigma_line N(0, 1) (x_j - x_i)`` with two
random elites ``x_i, x_j``. Sigmas are fractions of each gene's range (the paper's 0.01 and
0.2 are for genomes in [0, 1]); children are clipped into the box.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from evomotion.core.archives import ArchiveState, add
from evomotion.core.checks import MAX_POP_SIZE, check_choice, check_fields, check_number
from evomotion.core.optimizer import MutateFn
from evomotion.core.problem import GenomeSpec, MeasureSpec
from evomotion.core.qd import ArchiveConfig, QDOptimizer, as_measures
from evomotion.core.state import replaced


@dataclass(frozen=True)
class MAPElitesConfig(ArchiveConfig):
    """Settings of MAP-Elites (``[algorithm]`` with ``name = "map_elites"``)."""

    name: str = "map_elites"
    pop_size: int = 100  # genomes per generation (a batch of variations)
    initial: int = 0  # random genomes of the first generation; 0 = pop_size
    variation: str = "iso_line"  # iso_line (Vassiliades & Mouret 2018) | gaussian
    sigma_iso: float = 0.01  # fraction of each gene's range
    sigma_line: float = 0.2
    sigma: float = 0.05  # gaussian variation, fraction of each gene's range

    needs_measures = True  # class attribute, not a setting

    def validate(self) -> None:
        check_fields(self, "algorithm")
        check_number("algorithm.pop_size", self.pop_size, lo=1, hi=MAX_POP_SIZE, integer=True)
        check_number("algorithm.initial", self.initial, lo=0, hi=MAX_POP_SIZE, integer=True)
        check_choice("algorithm.variation", self.variation, ("iso_line", "gaussian"))
        for key in ("sigma_iso", "sigma_line", "sigma"):
            check_number(f"algorithm.{key}", getattr(self, key), lo=0.0)
        self.validate_archive()


@dataclass
class MAPElitesState:
    archive: ArchiveState
    pop: np.ndarray  # the last asked batch [n, d]
    cost: np.ndarray  # its costs (inf before tell)
    best_x: np.ndarray
    best_cost: float
    generation: int = 0
    evaluations: int = 0


class MAPElites(QDOptimizer):
    """MAP-Elites (Mouret & Clune 2015) with Iso+LineDD or Gaussian variation."""

    name = "map_elites"

    def __init__(self, genome: GenomeSpec, cfg: MAPElitesConfig | None = None, *,
                 measures: MeasureSpec | None = None) -> None:
        cfg = cfg or MAPElitesConfig()
        cfg.validate()
        super().__init__(genome, cfg, measures)

    def init(self, rng: np.random.Generator,
             population: np.ndarray | None = None) -> MAPElitesState:
        """An empty archive; the first ask returns ``population`` (when given) topped up
        with uniform random genomes to ``initial``."""
        d = self.genome.dim
        n0 = self.cfg.initial or self.cfg.pop_size
        x0 = self.genome.sample(rng, n0)
        if population is not None:
            p = np.asarray(population, dtype=float)
            if p.ndim != 2 or p.shape[1] != d:
                raise ValueError(f"map_elites: initial population has shape {p.shape}, "
                                 f"want (k, {d})")
            p = np.clip(p, self.genome.lower, self.genome.upper)
            x0[: min(n0, len(p))] = p[:n0]
        archive = self.spec.init(rng, d)
        return MAPElitesState(archive, x0, np.full(n0, math.inf),
                              self.genome.lower + 0.5 * self.genome.span, math.inf)

    def _ask(self, state: MAPElitesState, rng: np.random.Generator):
        if state.evaluations == 0 or not state.archive.occupied.any():
            x = state.pop if state.evaluations == 0 else \
                self.genome.sample(rng, self.cfg.pop_size)
            return x, replaced(state, pop=x, cost=np.full(len(x), math.inf))
        n, cfg = self.cfg.pop_size, self.cfg
        parents = self.random_elites(state.archive, rng, n)
        if cfg.variation == "iso_line":
            others = self.random_elites(state.archive, rng, n)
            x = parents + cfg.sigma_iso * self.span * rng.standard_normal(parents.shape) \
                + cfg.sigma_line * rng.standard_normal((n, 1)) * (others - parents)
        else:
            x = parents + cfg.sigma * self.span * rng.standard_normal(parents.shape)
        x = np.clip(x, self.genome.lower, self.genome.upper)
        return x, replaced(state, pop=x, cost=np.full(n, math.inf))

    def _tell(self, state: MAPElitesState, genomes: np.ndarray, cost: np.ndarray,
              rng: np.random.Generator, measures: np.ndarray | None = None) -> MAPElitesState:
        m = as_measures(measures, len(genomes), self.spec.measure_dim)
        archive, _, _ = add(self.spec, state.archive, genomes, -cost, m)
        return replaced(state, archive=archive, pop=genomes, cost=cost.copy(),
                        evaluations=state.evaluations + len(genomes))


def make_map_elites(genome: GenomeSpec, cfg: MAPElitesConfig, *, mutate: MutateFn | None = None,
                    measures: MeasureSpec | None = None) -> MAPElites:
    """Factory for the ``ALGORITHMS`` registry (``"map_elites"``); ``mutate`` must be
    ``None`` (the variation operators are the algorithm's)."""
    if mutate is not None:
        raise ValueError("map_elites: its variation is Iso+LineDD or Gaussian; a mutate hook "
                         "is not supported")
    return MAPElites(genome, cfg, measures=measures)
