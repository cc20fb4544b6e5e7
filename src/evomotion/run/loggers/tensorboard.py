"""``run.loggers = ["tensorboard"]``: the stats.csv rows as TensorBoard scalars, live.

Event files go to ``<run>/tensorboard/`` (``tensorboard --logdir runs/`` shows every run), one
scalar per column and generation (the step): ``fitness/best``, ``fitness/mean``,
``fitness/median``, ``fitness/best_so_far``, ``run/evaluations``, ``run/evals_per_s``,
``run/diversity``, ``run/failed`` and ``study/<column>`` for each numeric column the study adds
(text columns and non-finite values are left out). Written with tensorboardX (protobuf and
numpy only), flushed every few seconds and when the run ends.

Resume: each run of the loop starts a new event file whose first event purges the steps from
its first generation on (TensorBoard's ``purge_step``), so the generations repeated after the
last checkpoint show once; readers that ignore purge events show both copies.
"""

from __future__ import annotations

import math
import time
from numbers import Real
from pathlib import Path
from typing import Any

from tensorboardX import SummaryWriter

from evomotion.run.context import RunContext
from evomotion.run.contracts import ReplayHook

FOLDER = "tensorboard"
FLUSH_S = 5
FITNESS = ("best", "mean", "median", "best_so_far")
RUN = ("evaluations", "evals_per_s", "diversity", "failed")
#: stats.csv columns that are not written (the step, the host's time, the population's range)
SKIP = frozenset(("generation", "wall_s", "min", "max", "std"))


def tag(column: str) -> str:
    """The TensorBoard tag of a stats.csv column."""
    if column in FITNESS:
        return f"fitness/{column}"
    return f"run/{column}" if column in RUN else f"study/{column}"


def scalars(row: dict[str, Any]) -> dict[str, float]:
    """``tag -> value`` of the numeric, finite values of a stats row that are written."""
    out = {}
    for k, v in row.items():
        if k in SKIP or isinstance(v, bool) or not isinstance(v, Real):
            continue
        v = float(v)
        if math.isfinite(v):
            out[tag(k)] = v
    return out


class Logger:
    def __init__(self, out_dir: Path, replay: ReplayHook | None = None) -> None:
        self.dir = Path(out_dir) / FOLDER
        self.writer: SummaryWriter | None = None

    def row(self, row: dict[str, Any]) -> None:
        step = int(row["generation"])
        if self.writer is None:  # the first row: the steps from here on are (re)written
            # a name that sorts after the older files even within one second
            self.writer = SummaryWriter(str(self.dir), purge_step=step, flush_secs=FLUSH_S,
                                        filename_suffix=f".{time.time_ns()}")
        for name, value in scalars(row).items():
            self.writer.add_scalar(name, value, step)

    def close(self) -> None:
        if self.writer is not None:
            self.writer.close()
            self.writer = None

    def finish(self, ctx: RunContext) -> None:
        """Nothing left to write: the rows went out live."""
