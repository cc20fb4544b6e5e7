"""Benchmark functions, vectorized over the population (all minimised, optimum 0).

Definitions as in Jamil & Yang (2013), "A literature survey of benchmark functions for global
optimization problems": sphere, Rosenbrock (valley), Rastrigin (A = 10), Ackley
(a = 20, b = 0.2, c = 2*pi). Default domains follow the same survey.

``problem.measures = "linear_projection"`` makes any of them a quality-diversity benchmark:
the behaviour descriptors of Fontaine et al., "Covariance Matrix Adaptation for the Rapid
Illumination of Behavior Space", GECCO 2020, section 5.1: ``b1 = sum_{i <= n/2} clip(x_i)``,
``b2 = sum_{i > n/2} clip(x_i)`` with ``clip(x) = x`` for ``|x| <= 5.12`` and ``5.12 / x``
otherwise, each in ``[-5.12 n/2, 5.12 n/2]`` (run it with ``algorithm.name = "cma_me"`` or
``"map_elites"``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evomotion.core.checks import check_fields, check_number
from evomotion.core.problem import Evaluation, GenomeSpec, MeasureSpec, Sense
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


MEASURES = ("none", "linear_projection")
CLIP = 5.12  # Fontaine et al. 2020: the clip bound of the linear projection


def linear_projection(x: np.ndarray) -> np.ndarray:
    """``[pop, 2]`` descriptors of Fontaine et al. 2020, section 5.1."""
    c = np.where(np.abs(x) <= CLIP, x, CLIP / np.where(x == 0, 1.0, x))
    h = x.shape[1] // 2
    return np.stack([c[:, :h].sum(1), c[:, h:].sum(1)], axis=1)


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
    measures: str = "none"  # none | linear_projection (QD benchmark, Fontaine et al. 2020)

    def validate(self) -> None:
        check_fields(self, "problem")
        lookup(FUNCTIONS, "function", self.name)
        if self.measures not in MEASURES:
            raise InputError(f"problem.measures: expected one of {', '.join(MEASURES)}, got "
                             f"{self.measures!r}")
        if self.measures != "none" and self.dim < 2:
            raise InputError("problem.dim must be >= 2 for problem.measures = "
                             f"{self.measures!r}")
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

    sense: Sense = "min"
    metric_names: tuple[str, ...] = ("distance_to_optimum",)

    def __init__(self, cfg: FunctionsConfig) -> None:
        cfg.validate()
        self.cfg = cfg
        self.fn, hw = FUNCTIONS[cfg.name]
        hw = cfg.half_width or hw
        self.genome = GenomeSpec.box(cfg.dim, -hw, hw)
        self.optimum = np.ones(cfg.dim) if cfg.name == "rosenbrock" else np.zeros(cfg.dim)
        self.measure_spec = None
        if cfg.measures == "linear_projection":
            h = cfg.dim // 2
            r = CLIP * np.array([h, cfg.dim - h], dtype=float)
            self.measure_spec = MeasureSpec(("b1", "b2"), -r, r, (100, 100))

    def evaluate(self, genomes: np.ndarray) -> Evaluation:
        x = np.asarray(genomes, dtype=float)
        dist = np.linalg.norm(x - self.optimum, axis=1)
        m = linear_projection(x) if self.measure_spec is not None else None
        return Evaluation(self.fn(x), {"distance_to_optimum": dist}, measures=m)
