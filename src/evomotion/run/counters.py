"""The run loop's counters: where a run is, as recorded in every checkpoint.

A checkpoint's JSON holds them under ``counters`` (checked by
:func:`evomotion.run.checkpoint.check_meta`); :meth:`Counters.to_json` writes the same keys in
the same order as the untyped dict the loop kept before, so checkpoints written by older
versions resume and newer ones read the same.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass
class Counters:
    """``generation`` (-1 before the first step), ``evaluations``, ``wall_s`` (the run's
    seconds over all its sessions), ``failed_total`` individuals, the stagnation histories
    ``hist_best``/``hist_mean`` (costs), the best individual's ``best_metrics``, the byte or
    row offsets of stats.csv, log.txt and the history file at the snapshot, ``stop_reason``
    (``None`` while running) and ``finished`` (``False`` while the final artifacts are due,
    ``True`` once written, ``None``: not recorded)."""

    generation: int = -1
    evaluations: int = 0
    wall_s: float = 0.0
    failed_total: int = 0
    hist_best: list[float] = field(default_factory=list)
    hist_mean: list[float] = field(default_factory=list)
    best_metrics: dict[str, float] = field(default_factory=dict)
    stats_offset: int = 0
    log_offset: int = 0
    history_offset: int = 0
    stop_reason: str | None = None
    finished: bool | None = None
    #: whether ``stop_reason`` is written (a new run's first snapshot did not hold it)
    reason_recorded: bool = field(default=False, repr=False, compare=False)

    def to_json(self) -> dict[str, Any]:
        """The checkpoint's ``counters`` object."""
        out: dict[str, Any] = {
            "generation": self.generation, "evaluations": self.evaluations,
            "wall_s": self.wall_s, "failed_total": self.failed_total,
            "hist_best": list(self.hist_best), "hist_mean": list(self.hist_mean),
            "best_metrics": dict(self.best_metrics), "stats_offset": self.stats_offset,
            "log_offset": self.log_offset, "history_offset": self.history_offset}
        if self.reason_recorded or self.stop_reason is not None:
            out["stop_reason"] = self.stop_reason
        if self.finished is not None:
            out["finished"] = self.finished
        return out

    @classmethod
    def from_json(cls, doc: dict[str, Any]) -> Counters:
        """The counters of a checkpoint (already checked); a key an older run folder lacks
        (``history_offset``, ``stop_reason``, ``finished``) takes its default."""
        return cls(generation=int(doc["generation"]), evaluations=int(doc["evaluations"]),
                   wall_s=float(doc["wall_s"]), failed_total=int(doc["failed_total"]),
                   hist_best=list(doc["hist_best"]), hist_mean=list(doc["hist_mean"]),
                   best_metrics=dict(doc["best_metrics"]),
                   stats_offset=int(doc["stats_offset"]), log_offset=int(doc["log_offset"]),
                   history_offset=int(doc.get("history_offset", 0)),
                   stop_reason=doc.get("stop_reason"), finished=doc.get("finished"),
                   reason_recorded="stop_reason" in doc)
