"""The state of one run of the loop, and what one step did: what subscribers receive.

:class:`RunState` is the run as the loop holds it (the driver's state, the RNG, the typed
:class:`~evomotion.run.counters.Counters`, the log); :class:`StepRecord` is one step as the
subscribers of :mod:`evomotion.run.loop` see it (the driver's report, the ``stats.csv`` row,
the stop reason the step ended with, whether a checkpoint is due).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.run.config import Config
from evomotion.run.context import RunContext
from evomotion.run.counters import Counters
from evomotion.run.driver import Driver, StepReport
from evomotion.run.history import HistoryWriter
from evomotion.run.runlog import RunLog
from evomotion.run.stats import MemoryStats, StatsWriter


@dataclass
class RunState:
    """A run in progress: ``state`` and ``rng`` change with every step (``rng`` is the one
    the driver draws from); ``counters`` are recorded in every checkpoint."""

    study: Any  # a :class:`~evomotion.run.contracts.RunStudy`
    config: Config
    problem: Any
    driver: Driver
    state: Any
    rng: np.random.Generator
    counters: Counters
    log: RunLog
    out_dir: Path | None

    @property
    def sgn(self) -> float:
        """``fitness = sgn * cost``."""
        return -1.0 if self.driver.sense == "max" else 1.0

    def context(self, reason: str | None = None) -> RunContext:
        """The run as the study's hooks see it."""
        bx, bc = self.driver.best(self.state)
        c = self.counters
        return RunContext(self.study.name, self.out_dir, self.config, self.problem,
                          generation=c.generation, evaluations=c.evaluations, best_genome=bx,
                          best_fitness=self.sgn * bc, best_metrics=dict(c.best_metrics),
                          stop_reason=reason, log=self.log, driver=self.driver,
                          state=self.state)


@dataclass
class StepRecord:
    """One step: the driver's ``report``, its ``stats.csv`` ``row``, the stop ``reason`` it
    ended with (``None``: the run goes on) and whether a periodic checkpoint is ``due``."""

    report: StepReport
    row: dict[str, Any]
    reason: str | None
    due: bool


@dataclass
class RunFiles:
    """The files the loop appends to, whose offsets a snapshot records."""

    stats: StatsWriter | MemoryStats
    history: HistoryWriter | None
    log: RunLog

    def offsets(self) -> tuple[int, int, int]:
        return (self.stats.offset, self.log.offset,
                self.history.offset if self.history is not None else 0)
