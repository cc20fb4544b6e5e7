"""Exact validity of straight segments against blocked unit squares, by grid traversal.

A segment ``p0 -> p1`` is cut at every parameter ``t`` where it crosses a grid line
``x = k`` or ``y = k`` (Amanatides & Woo 1987 traversal, done for a whole batch at once).
Between two consecutive cuts the open piece lies inside one cell, or runs along a grid
line. Testing the cuts and the midpoints of the pieces therefore decides exactly which
closed squares and which open squares the segment meets; no sampling is involved.

Two validity rules (a segment must stay inside the map rectangle, whose outside counts as
blocked):

- ``"open"``  (the *free* model): the segment must not meet the interior of the obstacle
  region O (the union of the closed blocked squares and the outside of the map); touching
  O's boundary is allowed: running along an obstacle's edge, touching a corner, passing the
  pinch point between two diagonal blocked cells. An edge shared by two blocked cells is
  interior to O, so paths never slip between adjacent blocked cells;
- ``"closed"`` (the *centres* model): the segment must not touch a blocked cell at all,
  corners included (a diagonal step past a blocked corner is invalid, as in octile moves
  without corner cutting).

Coordinates within ``EPS`` (1e-9 cell) of a grid line count as on it, which absorbs the
rounding of ``x0 + t * dx``; for cell centres and corners (multiples of 0.5) the crossing
parameters themselves are exact.
"""

from __future__ import annotations

import numpy as np

EPS = 1e-9
RULES = ("open", "closed")


_PAD_CACHE: list = [None, None]  # (last blocked array, its padded copy)


def _padded(blocked: np.ndarray) -> np.ndarray:
    if _PAD_CACHE[0] is not blocked:
        _PAD_CACHE[:] = [blocked, np.pad(np.asarray(blocked, dtype=bool), 1,
                                         constant_values=True)]
    return _PAD_CACHE[1]


def _cuts(a0: np.ndarray, a1: np.ndarray) -> np.ndarray:
    """Parameters ``t[N, K]`` where coordinate ``a`` crosses an integer (padded with 1.0)."""
    moving = a1 != a0
    lo, hi = np.minimum(a0, a1), np.maximum(a0, a1)
    first = np.ceil(lo - EPS)
    count = np.where(moving, np.floor(hi + EPS) - first + 1, 0).astype(np.int64)
    k = int(count.max(initial=0))
    if k == 0:
        return np.ones((a0.size, 0))
    j = np.arange(k)
    d = np.where(moving, a1 - a0, 1.0)
    t = ((first[:, None] + j) - a0[:, None]) / d[:, None]
    t = np.minimum(np.maximum(t, 0.0), 1.0)
    t[j >= count[:, None]] = 1.0
    return t


def segments_valid(blocked: np.ndarray, p0: np.ndarray, p1: np.ndarray,
                   rule: str = "open") -> np.ndarray:
    """``valid[N]`` for segments ``p0[N, 2] -> p1[N, 2]`` (cell units, origin bottom-left).

    Segments are grouped by how many grid lines they cross (powers of two), so that a few
    long segments do not pad the arrays of many short ones.
    """
    if rule not in RULES:
        raise ValueError(f"unknown validity rule {rule!r}; available: {', '.join(RULES)}")
    p0 = np.asarray(p0, dtype=float).reshape(-1, 2)
    p1 = np.asarray(p1, dtype=float).reshape(-1, 2)
    n = p0.shape[0]
    if n == 0:
        return np.ones(0, dtype=bool)
    span = np.abs(p1 - p0).sum(axis=1)
    if n < 64 or span.max() <= 8:
        return _valid(blocked, p0, p1, rule)
    group = np.ceil(np.log2(span + 2)).astype(np.int64)
    out = np.empty(n, dtype=bool)
    for gval in np.unique(group):
        idx = np.flatnonzero(group == gval)
        out[idx] = _valid(blocked, p0[idx], p1[idx], rule)
    return out


def _valid(blocked: np.ndarray, p0: np.ndarray, p1: np.ndarray, rule: str) -> np.ndarray:
    n = p0.shape[0]
    t = np.concatenate([np.zeros((n, 1)), np.ones((n, 1)), _cuts(p0[:, 0], p1[:, 0]),
                        _cuts(p0[:, 1], p1[:, 1])], axis=1)
    t.sort(axis=1)
    t = np.concatenate([t, 0.5 * (t[:, 1:] + t[:, :-1])], axis=1)
    d = p1 - p0
    x = p0[:, :1] + t * d[:, :1]
    y = p0[:, 1:] + t * d[:, 1:]
    rx, ry = np.round(x), np.round(y)
    onx, ony = np.abs(x - rx) < EPS, np.abs(y - ry) < EPS
    pad = _padded(blocked)
    h, w = pad.shape
    cx = np.floor(np.where(onx, rx, x)).astype(np.int64) + 1
    cy = np.floor(np.where(ony, ry, y)).astype(np.int64) + 1
    np.clip(cx, 0, w - 1, out=cx)
    np.clip(cy, 0, h - 1, out=cy)
    hb, wb = np.asarray(blocked).shape
    inside = ((np.minimum(p0, p1) >= -EPS).all(1) & (np.maximum(p0[:, 0], p1[:, 0]) <= wb + EPS)
              & (np.maximum(p0[:, 1], p1[:, 1]) <= hb + EPS))  # the map is convex
    cxl = np.maximum(cx - onx, 0)  # the other cell when the point is on a vertical line
    cyl = np.maximum(cy - ony, 0)
    a, b, c, e = pad[cy, cx], pad[cy, cxl], pad[cyl, cx], pad[cyl, cxl]
    # a point lies in the closed cells around it; it is inside the obstacle region's interior
    # when all of them are blocked (an edge shared by two blocked cells is interior)
    hit = (a & b & c & e) if rule == "open" else (a | b | c | e)
    return inside & ~hit.any(axis=1)


def polyline_segments_valid(blocked: np.ndarray, points: np.ndarray,
                            rule: str = "open", chunk: int = 20000) -> np.ndarray:
    """``valid[P, S]`` for each segment of each polyline ``points[P, S + 1, 2]``."""
    points = np.asarray(points, dtype=float)
    P, S = points.shape[0], points.shape[1] - 1
    a = points[:, :-1].reshape(-1, 2)
    b = points[:, 1:].reshape(-1, 2)
    out = np.empty(a.shape[0], dtype=bool)
    for i in range(0, a.shape[0], chunk):
        out[i:i + chunk] = segments_valid(blocked, a[i:i + chunk], b[i:i + chunk], rule)
    return out.reshape(P, S)


def points_free(blocked: np.ndarray, xy: np.ndarray, rule: str = "open") -> np.ndarray:
    """Whether points ``xy[N, 2]`` are free (a zero-length segment at each point)."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    return segments_valid(blocked, xy, xy, rule)
