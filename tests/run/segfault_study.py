"""A test-only study whose problem segfaults its worker process for marked genomes.

``SegfaultProblem`` kills the process evaluating it with SIGSEGV (as a crash inside MuJoCo
would) whenever a batch holds a genome with ``x[0] > poison_above``. Outside a worker process
it raises instead, so that a mistake cannot kill the test runner. ``mode="nan"`` is the serial
stand-in: the same genomes get NaN fitness and metrics, i.e. exactly the worst-fitness,
failed, NaN-metrics result the process evaluator gives an individual that kills its worker.
Workers import this module from this folder (spawned workers get the parent's ``sys.path``).
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import time
from dataclasses import dataclass

import numpy as np

from evomotion.core.problem import Evaluation, GenomeSpec
from evomotion.studies.base import Study


@dataclass(frozen=True)
class SegfaultConfig:
    dim: int = 4
    poison_above: float = 4.6  # x[0] above this: the worker segfaults
    mode: str = "segfault"  # or "nan": NaN fitness and metrics instead (serial reference)
    sleep_s: float = 0.0  # per batch


class SegfaultProblem:
    sense = "max"
    metric_names = ("norm",)

    def __init__(self, cfg: SegfaultConfig) -> None:
        self.cfg = cfg
        self.genome = GenomeSpec.box(cfg.dim, -5.0, 5.0)

    def evaluate(self, x: np.ndarray) -> Evaluation:
        if self.cfg.sleep_s:
            time.sleep(self.cfg.sleep_s)
        poison = x[:, 0] > self.cfg.poison_above
        if poison.any() and self.cfg.mode == "segfault":
            if multiprocessing.parent_process() is None:
                raise RuntimeError("SegfaultProblem only segfaults inside a worker process")
            os.kill(os.getpid(), signal.SIGSEGV)
            time.sleep(10)  # the signal is delivered before this ends
        f = -(x**2).sum(1)
        norm = np.linalg.norm(x, axis=1)
        f[poison] = np.nan
        norm[poison] = np.nan
        return Evaluation(f, {"norm": norm})


STUDY = Study("segfault-toy", "test-only", SegfaultConfig, SegfaultProblem,
              defaults={"algorithm": {"pop_size": 24}, "run": {"generations": 5,
                                                                "checkpoint_every": 5}})
