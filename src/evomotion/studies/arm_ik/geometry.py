"""Vectorized 2-D segment geometry for paper 001's collision count and visibility tests.

Segments are arrays ``[..., 2, 2]`` = (endpoint, xy). Orientation ``orient(a, b, c) =
cross(b - a, c - a)`` is positive when ``c`` lies left of ``a -> b``. Two *closed* segments
intersect when they cross properly, when an endpoint of one lies on the other (touching), or
when they are collinear and overlap. The *strict* test counts only proper crossings (used for
visibility, where grazing an obstacle's vertex is allowed). ``eps`` (area units) treats tiny
orientations as collinear.
"""

from __future__ import annotations

import numpy as np


def orient(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """``cross(b - a, c - a)`` over broadcast points ``[..., 2]``."""
    return (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (
        c[..., 0] - a[..., 0]
    )


def _within(a: np.ndarray, b: np.ndarray, p: np.ndarray, eps: float) -> np.ndarray:
    """``p`` inside the bounding box of ``a, b`` (for points already known to be collinear)."""
    lo = np.minimum(a, b) - eps
    hi = np.maximum(a, b) + eps
    return np.all((p >= lo) & (p <= hi), axis=-1)


def _sign(d: np.ndarray, eps: float) -> np.ndarray:
    return np.where(d > eps, 1, np.where(d < -eps, -1, 0)).astype(np.int8)


def segments_intersect(p: np.ndarray, q: np.ndarray, strict: bool = False,
                       eps: float = 1e-12) -> np.ndarray:
    """Whether segments ``p[..., 2, 2]`` and ``q[..., 2, 2]`` intersect (broadcast)."""
    p, q = np.broadcast_arrays(np.asarray(p, dtype=float), np.asarray(q, dtype=float))
    if p.ndim == 2:  # a single pair
        return segments_intersect(p[None], q[None], strict, eps)[0]
    p1, p2, q1, q2 = p[..., 0, :], p[..., 1, :], q[..., 0, :], q[..., 1, :]
    s1, s2 = _sign(orient(q1, q2, p1), eps), _sign(orient(q1, q2, p2), eps)
    s3, s4 = _sign(orient(p1, p2, q1), eps), _sign(orient(p1, p2, q2), eps)
    hit = (s1 * s2 < 0) & (s3 * s4 < 0)
    if strict:
        return hit
    idx = np.nonzero((s1 == 0) | (s2 == 0) | (s3 == 0) | (s4 == 0))  # rare: check only these
    if idx[0].size:
        a1, a2, b1, b2 = p1[idx], p2[idx], q1[idx], q2[idx]
        touch = (
            ((s1[idx] == 0) & _within(b1, b2, a1, eps))
            | ((s2[idx] == 0) & _within(b1, b2, a2, eps))
            | ((s3[idx] == 0) & _within(a1, a2, b1, eps))
            | ((s4[idx] == 0) & _within(a1, a2, b2, eps))
        )
        hit[idx] |= touch
    return hit


def proper_crossings(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Strict test (proper crossings only, no tolerance) by orientation products, broadcast
    over ``p[..., 2, 2]`` and ``q[..., 2, 2]`` without materialising the broadcast inputs."""
    px1, py1, px2, py2 = p[..., 0, 0], p[..., 0, 1], p[..., 1, 0], p[..., 1, 1]
    qx1, qy1, qx2, qy2 = q[..., 0, 0], q[..., 0, 1], q[..., 1, 0], q[..., 1, 1]
    ex, ey, fx, fy = qx2 - qx1, qy2 - qy1, px2 - px1, py2 - py1
    a12 = (ex * (py1 - qy1) - ey * (px1 - qx1)) * (ex * (py2 - qy1) - ey * (px2 - qx1))
    a34 = (fx * (qy1 - py1) - fy * (qx1 - px1)) * (fx * (qy2 - py1) - fy * (qx2 - px1))
    return (a12 < 0) & (a34 < 0)


def segment_hits(segs: np.ndarray, obstacles: np.ndarray) -> np.ndarray:
    """``int[n, S]``: how many obstacle edges ``obstacles[M, 2, 2]`` each limb segment
    ``segs[n, S, 2, 2]`` meets. Fast path: proper crossings from the orientation products; only
    pairs where both products are ``<= 0`` without a proper crossing (touching, collinear) go
    through :func:`segments_intersect`."""
    n, s = segs.shape[:2]
    if obstacles.shape[0] == 0 or s == 0:
        return np.zeros((n, s), dtype=int)
    px1, py1 = segs[:, :, None, 0, 0], segs[:, :, None, 0, 1]
    px2, py2 = segs[:, :, None, 1, 0], segs[:, :, None, 1, 1]
    qx1, qy1 = obstacles[:, 0, 0], obstacles[:, 0, 1]
    qx2, qy2 = obstacles[:, 1, 0], obstacles[:, 1, 1]
    ex, ey = qx2 - qx1, qy2 - qy1
    fx, fy = px2 - px1, py2 - py1
    a12 = (ex * (py1 - qy1) - ey * (px1 - qx1)) * (ex * (py2 - qy1) - ey * (px2 - qx1))
    a34 = (fx * (qy1 - py1) - fy * (qx1 - px1)) * (fx * (qy2 - py1) - fy * (qx2 - px1))
    hit = (a12 < 0) & (a34 < 0)
    idx = np.nonzero((a12 <= 0) & (a34 <= 0) & ~hit)
    if idx[0].size:
        hit[idx] = segments_intersect(segs[idx[0], idx[1]], obstacles[idx[2]])
    return hit.sum(axis=2)


def count_intersections(segs: np.ndarray, obstacles: np.ndarray,
                        mask: np.ndarray | None = None) -> np.ndarray:
    """Number of (limb segment, obstacle edge) pairs that intersect, per individual.

    ``mask[S]`` or ``mask[n, S]`` selects the segments that count (padded zero-length bones
    are masked out). Returns ``int[n]``.
    """
    per = segment_hits(segs, obstacles)
    if mask is not None:
        per = per * np.broadcast_to(mask, per.shape)
    return per.sum(axis=1)


def points_in_polygons(pts: np.ndarray, polygons: list[np.ndarray]) -> np.ndarray:
    """Whether each point ``pts[..., 2]`` lies strictly inside any closed polygon (even-odd)."""
    inside = np.zeros(pts.shape[:-1], dtype=bool)
    x, y = pts[..., 0, None], pts[..., 1, None]
    for poly in polygons:
        a, b = poly[:-1], poly[1:]
        crosses = (a[:, 1] > y) != (b[:, 1] > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            xc = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
        inside ^= (np.count_nonzero(crosses & (x < xc), axis=-1) % 2).astype(bool)
    return inside
