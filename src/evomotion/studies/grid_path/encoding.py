"""The paper's fixed-length real path encoding in a frame rotated onto start -> goal.

Zhang et al. (2014, sec. 3.1, after Yan & Xiao 2012): the X' axis runs from the start S to
the goal G; the segment SG is divided into ``n`` equal parts and a perpendicular L_i is
drawn at each inner division point x'_i = i * |SG| / n (i = 1..n-1). A chromosome is the
vector of the ``n - 1`` coordinates y'_i, one on each perpendicular, and decodes to the
polyline S, P_1, ..., P_{n-1}, G with P_i = S + x'_i e + y'_i n (e along SG, n its left
normal; we put the frame's origin at S, which only shifts y' by a constant).

Reading of the paper's ``m`` (formula (2) is lost from the text; its explanation survives):
"m > 1 ensures the robot does not pass the same cell on different perpendiculars", i.e.
the spacing of the perpendiculars is at least ``m`` cell diagonals L' = sqrt(2):
``n = floor(|SG| / (m * sqrt(2)))``. On the paper's maps (S, G at opposite corner cells)
this gives 6, 11 and 17 genes for 10x10 (m = 1.2), 15x15 (m = 1.1) and 20x20 (m = 1.05).

Modes: ``discrete`` (the paper) snaps each P_i to the centre of the cell containing it;
``continuous`` keeps P_i as is. Gene bounds are the part of L_i inside the map.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from evomotion.core.problem import GenomeSpec
from evomotion.studies.grid_path.maps import GridMap

MODES = ("discrete", "continuous")
_INSET = 1e-6  # keep perpendicular ends strictly inside the map


def parts_from_m(length: float, m: float) -> int:
    """Number of equal parts of SG for the paper's ``m`` (at least 2)."""
    if m <= 0:
        raise ValueError(f"m must be > 0, got {m}")
    return max(2, int(math.floor(length / (m * math.sqrt(2.0)) + 1e-9)))


@dataclass(frozen=True)
class PerpendicularEncoding:
    """Geometry of the perpendiculars and the decoding of chromosomes into polylines."""

    start: np.ndarray  # S, cell units
    goal: np.ndarray  # G
    n_parts: int
    lower: np.ndarray  # y' bounds of each perpendicular inside the map
    upper: np.ndarray
    mode: str = "discrete"

    @classmethod
    def build(cls, m: GridMap, n_parts: int, mode: str = "discrete") -> PerpendicularEncoding:
        if mode not in MODES:
            raise ValueError(f"unknown encoding mode {mode!r}; available: {', '.join(MODES)}")
        S, G = m.start_xy, m.goal_xy
        enc = cls(S, G, int(n_parts), np.zeros(0), np.zeros(0), mode)
        base = enc.foot_points()
        normal = enc.normal
        lo = np.full(n_parts - 1, -np.inf)
        hi = np.full(n_parts - 1, np.inf)
        box = ((_INSET, m.width - _INSET), (_INSET, m.height - _INSET))
        for axis in (0, 1):
            if abs(normal[axis]) < 1e-15:
                continue
            a = (box[axis][0] - base[:, axis]) / normal[axis]
            b = (box[axis][1] - base[:, axis]) / normal[axis]
            lo, hi = np.maximum(lo, np.minimum(a, b)), np.minimum(hi, np.maximum(a, b))
        return cls(S, G, int(n_parts), lo, hi, mode)

    @property
    def length(self) -> float:
        return float(np.hypot(*(self.goal - self.start)))

    @property
    def direction(self) -> np.ndarray:
        return (self.goal - self.start) / self.length

    @cached_property
    def normal(self) -> np.ndarray:
        e = self.direction
        return np.array([-e[1], e[0]])

    @property
    def dim(self) -> int:
        return self.n_parts - 1

    def genome(self) -> GenomeSpec:
        return GenomeSpec(self.lower, self.upper, names=tuple(f"y{i + 1}" for i in
                                                              range(self.dim)))

    def foot_points(self) -> np.ndarray:
        """``[n-1, 2]`` division points x'_i on SG (where the perpendiculars cross it)."""
        return self._feet

    @cached_property
    def _feet(self) -> np.ndarray:
        i = np.arange(1, self.n_parts)[:, None]
        return self.start + (i / self.n_parts) * (self.goal - self.start)

    def points(self, genes: np.ndarray) -> np.ndarray:
        """``[pop, n-1, 2]`` points P_i on the perpendiculars (before snapping)."""
        genes = np.asarray(genes, dtype=float).reshape(-1, self.dim)
        return self.foot_points()[None] + genes[..., None] * self.normal

    def snap(self, pts: np.ndarray) -> np.ndarray:
        """Waypoints for the mode: cell centres (discrete) or the points themselves."""
        return np.floor(pts) + 0.5 if self.mode == "discrete" else pts

    def decode(self, genes: np.ndarray) -> np.ndarray:
        """Polylines ``[pop, n+1, 2]``: S, P_1..P_{n-1}, G in cell units."""
        inner = self.snap(self.points(genes))
        pop = inner.shape[0]
        S = np.broadcast_to(self.start, (pop, 1, 2))
        G = np.broadcast_to(self.goal, (pop, 1, 2))
        return np.concatenate([S, inner, G], axis=1)

    def to_genes(self, xy: np.ndarray) -> np.ndarray:
        """Inverse for points on the perpendiculars: ``y'_i = (P_i - foot_i) . n``."""
        return (np.asarray(xy, dtype=float) - self.foot_points()) @ self.normal


def polyline_length(points: np.ndarray) -> np.ndarray:
    """Euclidean length of each polyline ``points[pop, k, 2]``."""
    return np.hypot(*np.moveaxis(np.diff(points, axis=-2), -1, 0)).sum(axis=-1)
