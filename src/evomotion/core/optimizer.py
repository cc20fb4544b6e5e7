"""The ask/tell optimizer interface shared by the GA, cellular GA and CMA-ES.

State is explicit: an optimizer object holds only its (frozen) settings; everything that
changes lives in a state dataclass passed in and returned, so that a checkpoint is just
``state_to_arrays(state)`` plus the RNG state. Costs are always minimised (see
:mod:`evomotion.core.problem`). The public ``ask``/``tell`` validate and call the private
``_ask``/``_tell`` of each algorithm.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import numpy as np

from evomotion.core.problem import GenomeSpec


def check_rates(cfg: Any, *keys: str) -> None:
    """Raise ``ValueError`` unless every ``cfg.<key>`` is a probability in [0, 1]."""
    for key in keys:
        v = getattr(cfg, key)
        if not 0.0 <= v <= 1.0:
            raise ValueError(f"algorithm.{key} must be in [0, 1], got {v}")


class Optimizer(ABC):
    """Base class of ask/tell optimizers over a real-valued genome."""

    name: str = "optimizer"

    def __init__(self, genome: GenomeSpec) -> None:
        self.genome = genome

    @abstractmethod
    def init(self, rng: np.random.Generator) -> Any:
        """A fresh state; the first ``ask`` returns the initial population."""

    @abstractmethod
    def _ask(self, state: Any, rng: np.random.Generator) -> tuple[np.ndarray, Any]: ...

    @abstractmethod
    def _tell(self, state: Any, genomes: np.ndarray, cost: np.ndarray,
              rng: np.random.Generator) -> Any: ...

    @abstractmethod
    def best(self, state: Any) -> tuple[np.ndarray, float]:
        """Best genome seen so far and its cost (``inf`` before any tell)."""

    def ask(self, state: Any, rng: np.random.Generator) -> tuple[np.ndarray, Any]:
        genomes, state = self._ask(state, rng)
        if genomes.ndim != 2 or genomes.shape[1] != self.genome.dim:
            raise ValueError(f"{self.name}: ask returned shape {genomes.shape}")
        return genomes, state

    def tell(self, state: Any, genomes: np.ndarray, cost: np.ndarray,
             rng: np.random.Generator) -> Any:
        cost = np.asarray(cost, dtype=float)
        if cost.shape != (genomes.shape[0],):
            raise ValueError(f"{self.name}: {cost.shape} costs for {genomes.shape[0]} genomes")
        cost = np.where(np.isfinite(cost), cost, np.inf)
        return self._tell(state, genomes, cost, rng)

    def stop(self, state: Any) -> str | None:
        """The optimizer's own stopping reason (for example CMA-ES ``tolfun``), or ``None``."""
        return None

    def population(self, state: Any) -> tuple[np.ndarray, np.ndarray]:
        """Current population and its costs (for statistics and diversity)."""
        return state.pop, state.cost
