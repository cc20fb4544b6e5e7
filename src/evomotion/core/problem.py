"""The problem protocol: a genome declaration and a batch evaluation.

Every study exposes a :class:`Problem`. The engine never evaluates one individual at a
time: ``evaluate`` receives the whole batch ``genomes[pop, dim]`` and returns one fitness
per row plus named per-individual metrics (for example ``time_to_fall_s``).

Fitness is in the problem's own sense (``"max"`` or ``"min"``). Optimizers work on a
*cost* that is always minimised: ``cost = fitness`` for ``"min"`` and ``-fitness`` for
``"max"``. A non-finite fitness becomes the worst cost (``+inf``); see :func:`sanitize`.

Quality-diversity problems also describe *what* each individual does: ``measure_spec``
(a :class:`MeasureSpec`: names, ranges and units of the behaviour descriptors) and
``Evaluation.measures[pop, m]``. Both are optional; a problem without them is unchanged, and
the QD optimizers (MAP-Elites, CMA-ME) refuse it with a one-line message.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, Protocol, runtime_checkable

import numpy as np

Sense = Literal["min", "max"]


@dataclass(frozen=True)
class GenomeSpec:
    """Real-valued genome: ``dim`` genes with box bounds and optional named slices."""

    lower: np.ndarray
    upper: np.ndarray
    slices: dict[str, slice] = field(default_factory=dict)
    names: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        lo = np.asarray(self.lower, dtype=float).ravel()
        hi = np.asarray(self.upper, dtype=float).ravel()
        if lo.shape != hi.shape:
            raise ValueError(f"genome bounds differ in length: {lo.size} vs {hi.size}")
        if np.any(lo > hi):
            bad = int(np.argmax(lo > hi))
            raise ValueError(f"genome lower bound > upper bound at gene {bad}")
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)

    @property
    def dim(self) -> int:
        return int(self.lower.size)

    @property
    def span(self) -> np.ndarray:
        return self.upper - self.lower

    @classmethod
    def box(cls, dim: int, lower: float, upper: float) -> GenomeSpec:
        return cls(np.full(dim, float(lower)), np.full(dim, float(upper)))

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` genomes drawn uniformly inside the bounds."""
        return rng.uniform(self.lower, self.upper, size=(n, self.dim))


@dataclass(frozen=True)
class MeasureSpec:
    """The behaviour descriptors of a QD problem: ``names`` with units in them, the ranges
    ``lower``/``upper`` an archive spans, and a suggested number of grid ``bins`` each."""

    names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    bins: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        lo = np.asarray(self.lower, dtype=float).ravel()
        hi = np.asarray(self.upper, dtype=float).ravel()
        if lo.shape != hi.shape or lo.size != len(self.names) or not np.all(hi > lo):
            raise ValueError(f"measure ranges must be {len(self.names)} intervals lower < upper")
        bins = tuple(int(b) for b in self.bins) or (10,) * lo.size
        if len(bins) != lo.size or min(bins) < 1:
            raise ValueError(f"measure bins must be {lo.size} counts >= 1, got {bins}")
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)
        object.__setattr__(self, "bins", bins)

    @property
    def dim(self) -> int:
        return int(self.lower.size)


@dataclass
class Evaluation:
    """Result of evaluating a batch: ``fitness[pop]``, ``metrics[name][pop]`` and, for a
    quality-diversity problem, the behaviour descriptors ``measures[pop, m]``."""

    fitness: np.ndarray
    metrics: dict[str, np.ndarray] = field(default_factory=dict)
    failed: np.ndarray | None = None  # bool[pop]: non-finite or raised
    errors: list[str] = field(default_factory=list)  # messages of exceptions caught
    measures: np.ndarray | None = None  # [pop, m]; None: the problem has none

    def __len__(self) -> int:
        return int(self.fitness.shape[0])

    def failed_mask(self) -> np.ndarray:
        """``bool[pop]``: which individuals failed (``failed`` of ``None`` means none)."""
        if self.failed is None:
            return np.zeros(len(self), dtype=bool)
        return np.asarray(self.failed, dtype=bool)

    @staticmethod
    def concat(parts: list[Evaluation]) -> Evaluation:
        fit = np.concatenate([p.fitness for p in parts])
        # the metrics every part has (a failed part has the scalar ones only)
        keys = [k for k in parts[0].metrics if all(k in p.metrics for p in parts)] \
            if parts else []
        metrics = {k: np.concatenate([p.metrics[k] for p in parts]) for k in keys}
        failed = np.concatenate(
            [p.failed if p.failed is not None else np.zeros(len(p), bool) for p in parts]
        )
        errors = [e for p in parts for e in p.errors]
        dims = {p.measures.shape[1] for p in parts if p.measures is not None}
        measures = None
        if dims:  # a failed part (no measures) gets NaN rows
            m = dims.pop()
            measures = np.concatenate([p.measures if p.measures is not None
                                       else np.full((len(p), m), np.nan) for p in parts])
        return Evaluation(fit, metrics, failed, errors, measures)


@runtime_checkable
class Problem(Protocol):
    """What an optimizer needs from a study."""

    genome: GenomeSpec
    sense: Sense
    metric_names: tuple[str, ...]

    def evaluate(self, genomes: np.ndarray) -> Evaluation: ...


def worst_fitness(sense: Sense) -> float:
    return -np.inf if sense == "max" else np.inf


def to_cost(fitness: np.ndarray, sense: Sense) -> np.ndarray:
    """Fitness in the problem's sense -> cost to minimise (non-finite -> +inf)."""
    f = np.asarray(fitness, dtype=float)
    cost = -f if sense == "max" else f.copy()
    bad = ~np.isfinite(cost)
    if bad.any():
        cost[bad] = np.inf
    return cost


def sanitize(ev: Evaluation, sense: Sense, n: int) -> Evaluation:
    """Check shapes and turn NaN/inf fitness into the worst value, flagging it in ``failed``."""
    fit = np.asarray(ev.fitness, dtype=float).reshape(-1)
    if fit.shape[0] != n:
        raise ValueError(f"problem returned {fit.shape[0]} fitness values for {n} genomes")
    metrics = ev.metrics
    if not all(isinstance(v, np.ndarray) and v.shape[:1] == (n,) for v in metrics.values()):
        metrics = {k: v if isinstance(v, np.ndarray) and v.shape[:1] == (n,)
                   else np.asarray(v).reshape(n, *np.shape(v)[1:]) for k, v in metrics.items()}
    measures = ev.measures
    if measures is not None:
        measures = np.asarray(measures, dtype=float)
        if measures.ndim != 2 or measures.shape[0] != n:
            raise ValueError(f"problem returned measures of shape {measures.shape} for "
                             f"{n} genomes")
    # one reduction (a finite sum that overflows takes the exact path below)
    if ev.failed is None and math.isfinite(np.add.reduce(fit)) and (
            measures is None or np.isfinite(measures.sum())):  # the common clean batch
        return Evaluation(fit, metrics, None, ev.errors, measures)  # failed None: none failed
    bad = ~np.isfinite(fit)
    if measures is not None:
        bad |= ~np.isfinite(measures).all(axis=1)  # a NaN descriptor places nothing
    if ev.failed is not None:
        bad |= np.asarray(ev.failed, dtype=bool)
    if bad.any():
        fit = np.where(bad, worst_fitness(sense), fit)
    return Evaluation(fit, metrics, bad, list(ev.errors), measures)


def failed_evaluation(n: int, sense: Sense, metric_names: tuple[str, ...]) -> Evaluation:
    """An evaluation in which all ``n`` individuals failed (worst fitness, NaN metrics)."""
    return Evaluation(
        np.full(n, worst_fitness(sense)),
        {k: np.full(n, np.nan) for k in metric_names},
        np.ones(n, dtype=bool),
    )
