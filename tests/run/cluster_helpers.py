"""Test helpers for the Ray and Dask evaluator tests (``test_cluster_evaluators.py``).

``CrashProblem`` kills its worker process (as a simulator segfault would) whenever a chunk
holds a genome with ``x[0] > crash_above``; workers import it from this folder.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from evomotion.core.problem import Evaluation, GenomeSpec
from evomotion.run.evaluators import SerialEvaluator
from evomotion.run.stats import read_stats

HERE = Path(__file__).parent
DETERMINISTIC = ("generation", "evaluations", "best", "mean", "median", "min", "max", "std",
                 "best_so_far", "diversity", "failed")


@dataclass(frozen=True)
class CrashConfig:
    dim: int = 3
    crash_above: float = 0.95


class CrashProblem:
    sense = "min"
    metric_names = ("norm",)

    def __init__(self, cfg: CrashConfig) -> None:
        self.cfg = cfg
        self.genome = GenomeSpec.box(cfg.dim, -1.0, 1.0)

    def evaluate(self, x: np.ndarray) -> Evaluation:
        if np.any(x[:, 0] > self.cfg.crash_above):
            os._exit(3)  # the whole worker process dies, like a segfault in MuJoCo
        f = (x**2).sum(1)
        return Evaluation(f, {"norm": np.sqrt(f)})


def assert_same_evaluation(a: Evaluation, b: Evaluation) -> None:
    """Bit-identical fitness, failure flags, error messages and metrics."""
    assert a.fitness.tobytes() == b.fitness.tobytes()
    np.testing.assert_array_equal(a.failed_mask(), b.failed_mask())
    assert a.errors == b.errors
    assert sorted(a.metrics) == sorted(b.metrics)
    for k in a.metrics:
        assert np.asarray(a.metrics[k]).tobytes() == np.asarray(b.metrics[k]).tobytes(), k


def serial_evaluation(study, cfg, genomes: np.ndarray) -> Evaluation:
    return SerialEvaluator(study.make_problem, cfg)(genomes)


def assert_same_run(d1: Path, d2: Path) -> None:
    """Two run folders hold the same statistics and the same best individual."""
    s1, s2 = read_stats(d1 / "stats.csv"), read_stats(d2 / "stats.csv")
    for col in DETERMINISTIC:
        if col in s1:
            np.testing.assert_array_equal(s1[col], s2[col], err_msg=col)
    b1 = json.loads((d1 / "best.json").read_text())
    b2 = json.loads((d2 / "best.json").read_text())
    assert b1["genome"] == b2["genome"] and b1["fitness"] == b2["fitness"]
