"""The ask/tell optimizer interface shared by the GA, cellular GA and CMA-ES.

State is explicit and *replaced, never mutated*: an optimizer object holds only its frozen
settings; everything that changes lives in a state dataclass that ``ask``/``tell`` take and
return as a new object (``dataclasses.replace``), so that a checkpoint is just
``state_to_arrays(state)`` plus the RNG state. Randomness comes only from the ``rng`` passed
in. Costs are always minimised (see :mod:`evomotion.core.problem`).

The public ``ask``/``tell`` validate and call the private ``_ask``/``_tell`` of each algorithm;
``tell`` then does the bookkeeping every algorithm shares, once: the best genome and cost seen
so far (from the told genomes and costs; ``nan`` costs count as ``inf``) and the generation
counter. Every state dataclass therefore has the fields ``best_x``, ``best_cost`` and
``generation``. ``generation`` counts completed generations, the evaluation of the initial
population included: a ``tell`` completes one when :meth:`Optimizer.generation_done` says so
(always, except between the waves of an asynchronous cellular-GA sweep).

Quality-diversity optimizers (``needs_measures = True``) also get the behaviour descriptors
of the told genomes: ``tell(state, genomes, cost, rng, measures=m)`` passes them on to
``_tell(state, genomes, cost, rng, measures)``; every other optimizer ignores the keyword.

Construction is uniform: every registered factory is ``factory(genome, cfg, *, mutate=None)``
(see :mod:`evomotion.core.algorithms`), where ``mutate`` is a problem-supplied mutation
:data:`MutateFn`; an algorithm that cannot use one raises ``ValueError``. Every
``init(rng, population=None)`` accepts an optional initial population.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import Any

import numpy as np

from evomotion.core.problem import GenomeSpec
from evomotion.core.state import replaced as replace
from evomotion.core.state import state_to_arrays

#: ``mutate(x[n, d], rng, rate) -> x'``: a problem-supplied mutation replacing the registry one
MutateFn = Callable[[np.ndarray, np.random.Generator, float], np.ndarray]


def check_rates(cfg: Any, *keys: str) -> None:
    """Raise ``ValueError`` unless every ``cfg.<key>`` is a probability in [0, 1]."""
    for key in keys:
        v = getattr(cfg, key)
        if not 0.0 <= v <= 1.0:
            raise ValueError(f"algorithm.{key} must be in [0, 1], got {v}")


#: the largest state :meth:`Optimizer.check_next_step` copies and tries (bytes of arrays)
MAX_CHECKED_BYTES = 64 * 2**20


class Optimizer(ABC):
    """Base class of ask/tell optimizers over a real-valued genome."""

    name: str = "optimizer"
    needs_measures: bool = False  # QD optimizers: tell needs the behaviour descriptors
    extra_columns: tuple[str, ...] = ()  # the optimizer's own stats.csv columns (qd_stats)

    def __init__(self, genome: GenomeSpec, *, mutate: MutateFn | None = None) -> None:
        self.genome = genome
        self.mutate = mutate

    @abstractmethod
    def init(self, rng: np.random.Generator, population: np.ndarray | None = None) -> Any:
        """A fresh state; the first ``ask`` returns the initial population (``population``
        when given, see each algorithm for what it does with it)."""

    @abstractmethod
    def _ask(self, state: Any, rng: np.random.Generator) -> tuple[np.ndarray, Any]: ...

    @abstractmethod
    def _tell(self, state: Any, genomes: np.ndarray, cost: np.ndarray,
              rng: np.random.Generator, measures: np.ndarray | None = None) -> Any:
        """The algorithm's update; ``best_x``, ``best_cost`` and ``generation`` are left to
        :meth:`tell`. ``measures`` is ``None`` unless the optimizer ``needs_measures`` (QD)."""

    def ask(self, state: Any, rng: np.random.Generator) -> tuple[np.ndarray, Any]:
        """Genomes to evaluate next, and the new state."""
        genomes, state = self._ask(state, rng)
        if genomes.ndim != 2 or genomes.shape[1] != self.genome.dim:
            raise ValueError(f"{self.name}: ask returned shape {genomes.shape}")
        return genomes, state

    def tell(self, state: Any, genomes: np.ndarray, cost: np.ndarray,
             rng: np.random.Generator, measures: np.ndarray | None = None) -> Any:
        """The new state after the evaluated ``genomes`` got ``cost`` (minimised) and, for a
        QD optimizer, ``measures[n, m]`` (``None``: none, e.g. every individual failed)."""
        genomes = np.asarray(genomes)
        cost = np.asarray(cost, dtype=float)
        if genomes.ndim != 2 or genomes.shape[1] != self.genome.dim:
            raise ValueError(f"{self.name}: tell got genomes of shape {genomes.shape}")
        if cost.shape != (genomes.shape[0],):
            raise ValueError(f"{self.name}: {cost.shape} costs for {genomes.shape[0]} genomes")
        if not math.isfinite(np.add.reduce(cost)):  # one reduction; exact check below
            cost = np.where(np.isfinite(cost), cost, np.inf)
        new = self._tell(state, genomes, cost, rng, measures if self.needs_measures else None)
        changes: dict[str, Any] = {}
        if cost.size:
            i = int(cost.argmin())  # the first of equal minima
            if cost[i] < new.best_cost:
                changes.update(best_x=np.array(genomes[i], dtype=float),
                               best_cost=float(cost[i]))
        if self.generation_done(new):
            changes["generation"] = new.generation + 1
        return replace(new, **changes) if changes else new

    def check_next_step(self, state: Any) -> None:
        """Raise ``ValueError`` or ``TypeError`` unless a restored ``state`` can take one more
        generation: one ``ask`` and one ``tell`` (every cost 0, no measures) on a copy, with a
        generator of its own, must run and ask finite genomes. A damaged checkpoint whose
        shapes or values break only inside the next generation is refused on resume instead.
        States over :data:`MAX_CHECKED_BYTES` (a full covariance of thousands of genes) are
        not tried."""
        import copy
        import warnings

        if sum(a.nbytes for a in state_to_arrays(state)[0].values()) > MAX_CHECKED_BYTES:
            return  # the arrays a checkpoint holds, nested states' too
        trial = copy.deepcopy(state)
        rng = np.random.default_rng(0)
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            genomes, trial = self.ask(trial, rng)
            if not np.isfinite(genomes).all():
                raise ValueError(f"{self.name}: the state asks for non-finite genomes")
            self.tell(trial, genomes, np.zeros(len(genomes)), rng, None)

    def qd_stats(self, state: Any) -> dict[str, float]:
        """Values of :attr:`extra_columns` for ``stats.csv`` (none for plain optimizers)."""
        return {}

    def expected_population(self) -> int | None:
        """Rows of :meth:`population` (``None``: not fixed); checked on resume."""
        return getattr(getattr(self, "cfg", None), "pop_size", None)

    def best(self, state: Any) -> tuple[np.ndarray, float]:
        """Best genome seen so far and its cost (``inf`` before any tell)."""
        return state.best_x, float(state.best_cost)

    def center(self, state: Any) -> np.ndarray:
        """The point the method would deploy: the best genome seen here; the evolution
        strategies (:mod:`evomotion.core.es`) override it with their distribution mean."""
        return np.asarray(self.best(state)[0], dtype=float)

    def generation_done(self, state: Any) -> bool:
        """Whether the ``tell`` that returned ``state`` completed a generation."""
        return True

    def end_of_generation(self, state: Any) -> bool:
        """Alias of :meth:`generation_done` (kept for existing callers)."""
        return self.generation_done(state)

    def stop(self, state: Any) -> str | None:
        """The optimizer's own stopping reason (for example CMA-ES ``tolfun``), or ``None``."""
        return None

    def population(self, state: Any) -> tuple[np.ndarray, np.ndarray]:
        """Current population and its costs (for statistics and diversity)."""
        return state.pop, state.cost
