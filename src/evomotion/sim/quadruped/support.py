"""Support margin from contact forces: centre of pressure against the support polygon.

With foot contact points ``p_i`` (floor plane, metres) and normal forces ``f_i >= 0``, the
centre of pressure is ``c = sum f_i p_i / sum f_i`` (on a flat floor it coincides with the
zero-moment point; Vukobratović & Borovac, "Zero-moment point - thirty five years of its
life", Int. J. Humanoid Robotics 1(1), 2004). The margin is the signed distance of ``c`` to the
boundary of the convex hull of the feet in contact (> 0 inside): the least distance to the
lines of the hull's edges. Because forces only push, ``c`` lies in the hull, so the margin is
>= 0 up to numerical noise; it falls to 0 when the load moves onto one edge (the robot is
about to tip over it). Defined only with at least 3 feet in contact (NaN otherwise); three or
more collinear feet give 0.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

_PAIRS = tuple(combinations(range(4), 2))
_TOL = 1e-12  # [m]: collinearity tolerance of the hull-edge test


def _cross(ex: np.ndarray, ey: np.ndarray, vx: np.ndarray, vy: np.ndarray) -> np.ndarray:
    return ex * vy - ey * vx


def support_margins(points: np.ndarray, forces: np.ndarray, min_force: float = 0.0
                    ) -> tuple[np.ndarray, np.ndarray]:
    """``(margin[T], cop[T, 2])`` for contact points ``points[T, n, 2]`` [m] and normal
    forces ``forces[T, n]`` [N] of ``n <= 4`` feet; a foot is in contact when its force
    exceeds ``min_force``. Margin NaN where fewer than 3 feet are in contact; COP NaN where
    none is."""
    pts = np.asarray(points, dtype=float)
    f = np.asarray(forces, dtype=float)
    n = pts.shape[-2]
    if n > 4:
        raise ValueError("at most 4 feet")
    on = f > min_force
    w = np.where(on, f, 0.0)
    total = w.sum(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        cop = (w[..., None] * pts).sum(axis=-2) / total[..., None]
    margin = np.full(f.shape[:-1], np.inf)
    for i, j in (pair for pair in _PAIRS if pair[1] < n):
        ex, ey = pts[..., j, 0] - pts[..., i, 0], pts[..., j, 1] - pts[..., i, 1]
        length = np.hypot(ex, ey)
        lo = np.zeros_like(length)
        hi = np.zeros_like(length)
        for k in (k for k in range(n) if k not in (i, j)):
            side = _cross(ex, ey, pts[..., k, 0] - pts[..., i, 0], pts[..., k, 1] - pts[..., i, 1])
            lo = np.where(on[..., k], np.minimum(lo, side), lo)
            hi = np.where(on[..., k], np.maximum(hi, side), hi)
        tol = _TOL * np.maximum(length, 1.0)
        edge = on[..., i] & on[..., j] & (length > tol) & ((lo >= -tol) | (hi <= tol))
        sign = np.where(hi > tol, 1.0, np.where(lo < -tol, -1.0, 0.0))  # 0: all collinear
        with np.errstate(invalid="ignore", divide="ignore"):
            dist = sign * _cross(ex, ey, cop[..., 0] - pts[..., i, 0],
                                 cop[..., 1] - pts[..., i, 1]) / length
        margin = np.where(edge, np.minimum(margin, dist), margin)
    margin = np.where(on.sum(axis=-1) >= 3, margin, np.nan)
    return np.where(np.isinf(margin), 0.0, margin), cop


def support_margin(points: np.ndarray, forces: np.ndarray, min_force: float = 0.0) -> float:
    """The margin [m] of one contact set ``points[n, 2]``, ``forces[n]``
    (see :func:`support_margins`)."""
    m, _ = support_margins(np.asarray(points, dtype=float)[None],
                           np.asarray(forces, dtype=float)[None], min_force)
    return float(m[0])
