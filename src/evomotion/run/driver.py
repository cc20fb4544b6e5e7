"""The driver seam: a run is a sequence of steps of a driver with explicit state.

The run loop (:mod:`evomotion.run.runner`) owns the run folder, config, log, stats, best.json,
checkpoints, console and evaluator; a driver owns the method. Each :meth:`Driver.step` does one
unit of work (a generation of an ask/tell optimizer, a generation of a multi-phase schedule, a
batch of search expansions) and returns the new state with a :class:`StepReport`. A driver never
writes files and never prints.

Costs are minimised (``cost = fitness`` for ``sense == "min"``, ``-fitness`` for ``"max"``),
as everywhere in the engine. A driver state must survive :meth:`Driver.state_arrays` /
:meth:`Driver.restore` exactly (npz arrays + JSON meta, no pickle): that is what makes resume
bit-identical.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from evomotion.core.problem import Evaluation
from evomotion.core.state import state_from_arrays, state_to_arrays

#: ``evaluate(genomes[n, d]) -> Evaluation``: the run's evaluator (sanitized fitness)
Evaluate = Callable[[np.ndarray], Evaluation]


@dataclass
class StepReport:
    """What one step did, for the run's statistics and log.

    ``cost`` and ``population`` describe the population after the step (``population`` may be
    ``None`` where there is none, e.g. a search); ``best_metrics`` holds the metrics of the
    step's best individual when it improved the best so far; ``extras`` are the study's own
    ``stats.csv`` columns (:attr:`Driver.extra_columns`); ``lines`` go to ``log.txt``.
    """

    evaluations: int
    cost: np.ndarray
    population: np.ndarray | None = None
    failed: int = 0
    errors: list[str] = field(default_factory=list)
    best_metrics: dict[str, float] | None = None
    extras: dict[str, Any] = field(default_factory=dict)
    lines: list[str] = field(default_factory=list)


class Driver(ABC):
    """A method stepped by the run loop. Subclasses set ``sense`` and implement the steps.

    - ``uses_evaluator``: False for methods with no batch evaluation (searches); the run loop
      then refuses a non-serial evaluator instead of ignoring it.
    - ``snapshot_every_step``: True when a state can be snapshotted cheaply after every step
      (then Ctrl-C loses nothing); False when the state is large and mutated in place (a
      search's OPEN/CLOSED lists): snapshots are then taken at checkpoints only, so an
      interruption costs at most one checkpoint interval.
    """

    sense: str = "min"
    extra_columns: tuple[str, ...] = ()
    uses_evaluator: bool = True
    snapshot_every_step: bool = True

    def check_new_run(self) -> None:
        """Checks of a new run's own inputs (a file it starts from), before its folder is
        made: one :class:`~evomotion.errors.InputError` line if one is wrong. A resume does not
        call it (its state is in the checkpoint). Default: none."""

    @abstractmethod
    def init(self, rng: np.random.Generator) -> Any:
        """A fresh state (nothing evaluated yet)."""

    @abstractmethod
    def step(self, state: Any, rng: np.random.Generator,
             evaluate: Evaluate) -> tuple[Any, StepReport]:
        """One unit of work; returns the new state and its report."""

    @abstractmethod
    def best(self, state: Any) -> tuple[np.ndarray, float]:
        """Best genome so far and its cost (``inf`` before any step)."""

    def stop(self, state: Any) -> str | None:
        """The method's own stopping reason (``"solved"``, ``"tolfun"``, ...) or ``None``."""
        return None

    def state_type(self) -> type:
        """The dataclass type of this driver's state (for :meth:`restore`)."""
        return type(self.init(np.random.default_rng(0)))

    def state_arrays(self, state: Any) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """The state as (npz arrays, JSON meta), copied so that later steps cannot alter it."""
        arrays, meta = state_to_arrays(state)
        return {k: np.array(v, copy=True) for k, v in arrays.items()}, meta

    def restore(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> Any:
        """Inverse of :meth:`state_arrays`."""
        return state_from_arrays(self.state_type(), arrays, meta)

    def archive_view(self, state: Any) -> tuple[Any, Any, tuple[str, ...]] | None:
        """``(archive spec, archive state, measure names)`` of a quality-diversity method
        (the run loop writes ``archive.npz`` and the heat map from it), else ``None``."""
        return None

    def check_state(self, state: Any) -> None:
        """Raise ``ValueError`` naming what is wrong when a restored ``state`` cannot belong
        to this driver's run (shapes against the config, non-finite genomes, ...)."""

    def close(self) -> None:
        """Release resources (called once at the end of a run)."""
