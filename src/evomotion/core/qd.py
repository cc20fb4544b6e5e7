"""What the quality-diversity optimizers share: the archive settings, the measures hook,
and the per-generation QD statistics (coverage, QD-score, best, archive size).

A QD optimizer is an :class:`~evomotion.core.optimizer.Optimizer` that also receives the
behaviour descriptors of what it asked for (``tell(..., measures=...)``); its factory gets
the problem's :class:`~evomotion.core.problem.MeasureSpec`. Its state holds the archive
(:mod:`evomotion.core.archives`) as a nested state, so checkpoints and resume hold the
archive exactly. ``population`` is the last evaluated batch; the archive's elites are what
``archive(state)`` returns.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from evomotion.core.archives import ArchiveSpec, ArchiveState, stats
from evomotion.core.checks import check_choice, check_number
from evomotion.core.optimizer import Optimizer
from evomotion.core.problem import GenomeSpec, MeasureSpec

#: the ``stats.csv`` columns every QD optimizer adds
QD_COLUMNS = ("archive_size", "coverage", "qd_score", "qd_best")
MAX_CELLS = 10**7


@dataclass(frozen=True)
class ArchiveConfig:
    """Archive fields of every QD ``[algorithm]`` section.

    ``archive``: "grid" (``bins`` per measure; 0 = the problem's suggestion) or "cvt"
    (``cells`` centroids by k-means on ``cvt_samples`` uniform samples, from the run seed).
    ``qd_offset``: QD-score = sum over filled cells of (objective - ``qd_offset``), with
    objective = fitness (maximised problems) or -fitness (minimised ones)."""

    archive: str = "grid"
    bins: int = 0
    cells: int = 1000
    cvt_samples: int = 100_000
    qd_offset: float = 0.0

    def validate_archive(self) -> None:
        check_choice("algorithm.archive", self.archive, ("grid", "cvt"))
        check_number("algorithm.bins", self.bins, lo=0, hi=MAX_CELLS, integer=True)
        check_number("algorithm.cells", self.cells, lo=1, hi=MAX_CELLS, integer=True)
        check_number("algorithm.cvt_samples", self.cvt_samples, lo=1, hi=10**8, integer=True)
        if self.archive == "cvt" and self.cvt_samples < self.cells:
            raise ValueError(f"algorithm.cvt_samples must be >= algorithm.cells "
                             f"({self.cells}), got {self.cvt_samples}")


def archive_spec(cfg: ArchiveConfig, measures: MeasureSpec) -> ArchiveSpec:
    """The archive a config describes over the problem's measure box."""
    if cfg.archive == "cvt":
        return ArchiveSpec("cvt", measures.lower, measures.upper, cells_cvt=cfg.cells,
                           samples=cfg.cvt_samples)
    bins = (cfg.bins,) * measures.dim if cfg.bins else measures.bins
    if int(np.prod(bins, dtype=float)) > MAX_CELLS:
        raise ValueError(f"algorithm.bins: {bins} make more than {MAX_CELLS} cells")
    return ArchiveSpec("grid", measures.lower, measures.upper, bins=tuple(bins))


class QDOptimizer(Optimizer):
    """Base of MAP-Elites and CMA-ME: the archive and the QD statistics."""

    needs_measures = True
    extra_columns = QD_COLUMNS

    def __init__(self, genome: GenomeSpec, cfg: Any, measures: MeasureSpec | None) -> None:
        if measures is None:
            raise ValueError(f"{self.name}: a quality-diversity optimizer needs a problem "
                             "with measures (behaviour descriptors); this one has none")
        super().__init__(genome)
        self.cfg = cfg
        self.measure_spec = measures
        self.spec = archive_spec(cfg, measures)
        self.span = np.where(genome.span > 0, genome.span, 1.0)

    def result_archive(self, state: Any) -> ArchiveState:
        """The elitist archive whose elites a run hands over (CMA-MAE keeps it beside its
        thresholded one)."""
        return state.archive

    def qd_stats(self, state: Any) -> dict[str, float]:
        return stats(self.result_archive(state), self.cfg.qd_offset)

    def expected_population(self) -> int | None:
        return None  # the batch size is the algorithm's, checked by its own tell

    def population(self, state: Any) -> tuple[np.ndarray, np.ndarray]:
        return state.pop, state.cost

    def random_elites(self, archive: ArchiveState, rng: np.random.Generator,
                      n: int) -> np.ndarray:
        """``n`` elites drawn uniformly (with replacement) from the filled cells."""
        filled = np.flatnonzero(archive.occupied)
        return archive.solutions[filled[rng.integers(0, filled.size, size=n)]]


def as_measures(measures: np.ndarray | None, n: int, m: int) -> np.ndarray:
    """``measures[n, m]`` as floats; ``None`` (every individual failed) becomes NaN rows."""
    if measures is None:
        return np.full((n, m), np.nan)
    out = np.asarray(measures, dtype=float)
    if out.shape != (n, m):
        raise ValueError(f"tell got measures of shape {out.shape}, expected ({n}, {m})")
    return out
