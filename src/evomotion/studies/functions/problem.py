"""Benchmark functions, vectorized over the population (all minimised, optimum 0).

Definitions as in Jamil & Yang (2013), "A literature survey of benchmark functions for global
optimization problems": sphere, Rosenbrock (valley), Rastrigin (A = 10), Ackley
(a = 20, b = 0.2, c = 2*pi). Default domains follow the same survey.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evomotion.core.checks import check_fields, check_number
from evomotion.core.problem import Evaluation, GenomeSpec
from evomotion.core.registry import lookup
from evomotion.errors import InputError


def sphere(x: np.ndarray) -> np.ndarray:
    return np.sum(x * x, axis=1)


def rosenbrock(x: np.ndarray) -> np.ndarray:
    return np.sum(100.0 * (x[:, 1:] - x[:, :-1] ** 2) ** 2 + (1.0 - x[:, :-1]) ** 2, axis=1)


def rastrigin(x: np.ndarray) -> np.ndarray:
    return 10.0 * x.shape[1] + np.sum(x * x - 10.0 * np.cos(2 * np.pi * x), axis=1)


def ackley(x: np.ndarray) -> np.ndarray:
    d = x.shape[1]
    s1 = np.sqrt(np.sum(x * x, axis=1) / d)
    s2 = np.sum(np.cos(2 * np.pi * x), axis=1) / d
    return -20.0 * np.exp(-0.2 * s1) - np.exp(s2) + 20.0 + np.e


FUNCTIONS = {  # name -> (function, default half-width of the domain)
    "sphere": (sphere, 5.12),
    "rosenbrock": (rosenbrock, 2.048),
    "rastrigin": (rastrigin, 5.12),
    "ackley": (ackley, 32.768),
}


#: the largest ``problem.dim`` (a benchmark genome; refused before any array is built)
MAX_DIM = 1_000_000
#: the largest ``problem.half_width`` (squares and sums of genes stay finite)
MAX_HALF_WIDTH = 1e100


@dataclass(frozen=True)
class FunctionsConfig:
    """``[problem]`` of the functions study. ``half_width = 0`` uses the function's domain.

    ``dim`` is in ``[1, MAX_DIM]`` (``[2, MAX_DIM]`` for Rosenbrock), ``half_width`` a finite
    value in ``[0, MAX_HALF_WIDTH]``."""

    name: str = "sphere"
    dim: int = 30
    half_width: float = 0.0

    def validate(self) -> None:
        check_fields(self, "problem")
        lookup(FUNCTIONS, "function", self.name)
        if self.dim < 1:
            raise ValueError(f"problem.dim must be >= 1, got {self.dim}")
        if self.name == "rosenbrock" and self.dim < 2:
            raise ValueError("problem.dim must be >= 2 for rosenbrock")
        if self.dim > MAX_DIM:
            raise InputError(f"problem.dim: expected at most {MAX_DIM} genes, got {self.dim}")
        if self.half_width < 0:
            raise ValueError(f"problem.half_width must be >= 0, got {self.half_width}")
        check_number("problem.half_width", self.half_width, lo=0.0, hi=MAX_HALF_WIDTH)

    def genome_dim(self) -> int:
        """The genome's length (for the memory check before the problem is built)."""
        return self.dim


class FunctionProblem:
    """A benchmark function as a batch :class:`~evomotion.core.problem.Problem`."""

    sense = "min"
    metric_names = ("distance_to_optimum",)

    def __init__(self, cfg: FunctionsConfig) -> None:
        cfg.validate()
        self.cfg = cfg
        self.fn, hw = FUNCTIONS[cfg.name]
        hw = cfg.half_width or hw
        self.genome = GenomeSpec.box(cfg.dim, -hw, hw)
        self.optimum = np.ones(cfg.dim) if cfg.name == "rosenbrock" else np.zeros(cfg.dim)

    def evaluate(self, genomes: np.ndarray) -> Evaluation:
        x = np.asarray(genomes, dtype=float)
        dist = np.linalg.norm(x - self.optimum, axis=1)
        return Evaluation(self.fn(x), {"distance_to_optimum": dist})
