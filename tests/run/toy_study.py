"""A test-only study whose problem misbehaves on purpose (NaN, exceptions, slowness)."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from evomotion.core.problem import Evaluation, GenomeSpec
from evomotion.studies.base import Study


@dataclass(frozen=True)
class ToyConfig:
    dim: int = 6
    nan_above: float = 4.0  # x[0] above this -> NaN fitness
    raise_above: float = 4.6  # x[1] above this -> the batch raises
    sleep_s: float = 0.0


class ToyProblem:
    sense = "max"
    metric_names = ("norm",)

    def __init__(self, cfg: ToyConfig) -> None:
        self.cfg = cfg
        self.genome = GenomeSpec.box(cfg.dim, -5, 5)

    def evaluate(self, x: np.ndarray) -> Evaluation:
        if self.cfg.sleep_s:
            time.sleep(self.cfg.sleep_s)
        if np.any(x[:, 1] > self.cfg.raise_above):
            raise RuntimeError("simulated solver blow-up")
        f = -(x**2).sum(1)
        f[x[:, 0] > self.cfg.nan_above] = np.nan
        return Evaluation(f, {"norm": np.linalg.norm(x, axis=1)})


STUDY = Study("toy", "test-only", ToyConfig, ToyProblem,
              defaults={"algorithm": {"pop_size": 24}, "run": {"generations": 30,
                                                                "checkpoint_every": 5}})
