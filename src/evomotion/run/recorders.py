"""The run loop's per-step subscribers: stats, history, console, loggers and checkpoints.

Each is a :class:`~evomotion.run.contracts.Subscriber` of :mod:`evomotion.run.loop`; the
runner (:mod:`evomotion.run.runner`) builds the list. The checkpoint writer keeps the last
snapshot (driver state, RNG, counters and the files' offsets) so that a checkpoint written at a
stop, Ctrl-C or a crash replays exactly the steps that were lost.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.core.state import rng_state
from evomotion.run.checkpoint import save_checkpoint
from evomotion.run.console import Reporter
from evomotion.run.context import RunContext
from evomotion.run.contracts import Subscriber
from evomotion.run.history import HistoryWriter
from evomotion.run.loggers import Loggers
from evomotion.run.run_state import RunState, StepRecord
from evomotion.run.stats import MemoryStats, StatsWriter

#: the ``(stats_offset, log_offset, history_offset)`` of the run's files now
Offsets = Callable[[], tuple[int, int, int]]
#: a checkpoint's arrays and its JSON
Snapshot = tuple[dict[str, np.ndarray], dict[str, Any]]


class StatsRecorder(Subscriber):
    """One ``stats.csv`` row per step (kept in memory by a run without a folder)."""

    def __init__(self, stats: StatsWriter | MemoryStats) -> None:
        self.stats = stats

    def on_step(self, run: RunState, step: StepRecord) -> None:
        self.stats.write(step.row)


class HistoryRecorder(Subscriber):
    """The population and its fitness every ``every`` generations (``run.history_every``)."""

    def __init__(self, history: HistoryWriter, every: int) -> None:
        self.history, self.every = history, every

    def on_step(self, run: RunState, step: StepRecord) -> None:
        rep = step.report
        if rep.population is not None and run.counters.generation % self.every == 0:
            self.history.write(run.counters.generation, rep.population,
                               run.sgn * np.asarray(rep.cost))


class ConsoleRecorder(Subscriber):
    """The progress bar or line on the console."""

    def __init__(self, reporter: Reporter) -> None:
        self.reporter = reporter

    def on_step(self, run: RunState, step: StepRecord) -> None:
        c = run.counters
        self.reporter.update(c.generation, step.row["best_so_far"], step.row["mean"],
                             c.evaluations)

    def on_close(self, run: RunState) -> None:
        self.reporter.close()


class LoggerRelay(Subscriber):
    """The extra loggers (``run.loggers``): every row live, their files at the end, after
    the study's artifacts (``best.motion``)."""

    def __init__(self, loggers: Loggers) -> None:
        self.loggers = loggers

    def on_step(self, run: RunState, step: StepRecord) -> None:
        self.loggers.row(step.row)

    def on_close(self, run: RunState) -> None:
        self.loggers.close()

    def on_finish(self, ctx: RunContext, code: int) -> int:
        self.loggers.finish(ctx)
        return code


class CheckpointWriter(Subscriber):
    """Snapshots after every step (drivers that allow it) or at checkpoints only, and the
    checkpoint files (:func:`~evomotion.run.checkpoint.save_checkpoint`) from the last one."""

    def __init__(self, out_dir: Path, record: dict[str, Any], offsets: Offsets) -> None:
        self.out_dir, self.record, self.offsets = out_dir, record, offsets
        self.snap: Snapshot | None = None

    def take(self, run: RunState) -> None:
        """Snapshot the run as it is now."""
        a, m = run.driver.state_arrays(run.state)
        meta: dict[str, Any] = {"state." + k: v for k, v in m.items()}
        stats_offset, log_offset, history_offset = self.offsets()
        counters = dataclasses.replace(run.counters, stats_offset=stats_offset,
                                       log_offset=log_offset, history_offset=history_offset)
        meta.update(rng=rng_state(run.rng), counters=counters.to_json(), config=self.record)
        self.snap = {"state." + k: v for k, v in a.items()}, meta

    def on_start(self, run: RunState) -> None:
        self.take(run)  # Ctrl-C in the first step still leaves a checkpoint

    def on_step(self, run: RunState, step: StepRecord) -> None:
        if run.driver.snapshot_every_step or step.due or step.reason is not None:
            self.take(run)

    def on_checkpoint(self, run: RunState) -> None:
        assert self.snap is not None
        save_checkpoint(self.out_dir, run.counters.generation, *self.snap)

    @property
    def counters(self) -> dict[str, Any]:
        """The last snapshot's counters (its JSON object, changed in place)."""
        assert self.snap is not None
        counters: dict[str, Any] = self.snap[1]["counters"]
        return counters

    def interrupted(self) -> None:
        """Ctrl-C: the snapshot is of an interrupted run, or, when the run had ended, of one
        whose final artifacts are due."""
        done = self.counters.get("stop_reason")
        if done in (None, "interrupted"):
            self.counters["stop_reason"] = "interrupted"
        else:
            self.counters["finished"] = False

    def save(self, arrays: bool = True) -> None:
        """The last snapshot as a checkpoint (``arrays=False``: its JSON only, when its
        arrays are written already)."""
        assert self.snap is not None
        save_checkpoint(self.out_dir, max(self.counters["generation"], 0),
                        self.snap[0] if arrays else None, self.snap[1])
