"""Planar polygon geometry for worlds (vectorised with numpy): signed distances of points to
simple polygons, point-in-polygon by the even-odd rule, and the simplicity test.

Units are the paper's; a polygon is an ``(n, 2)`` array of vertices in order (either sense),
closed implicitly. The planner's checks (:mod:`.terrain`) are built on these; the independent
checker (:mod:`.check`) uses its own formulas.
"""

from __future__ import annotations

import numpy as np


def edges(poly: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start and end points of the polygon's edges, each ``(n, 2)``."""
    return poly, np.roll(poly, -1, axis=0)


def segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance of points ``p[..., 2]`` to segments ``a[m, 2] -> b[m, 2]``: ``[..., m]``."""
    d = b - a
    n2 = np.maximum(np.einsum("mi,mi->m", d, d), 1e-300)
    rel = p[..., None, :] - a
    u = np.clip(np.einsum("...mi,mi->...m", rel, d) / n2, 0.0, 1.0)
    closest = a + u[..., None] * d
    return np.linalg.norm(p[..., None, :] - closest, axis=-1)


def inside(p: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Even-odd point-in-polygon for points ``p[..., 2]`` (boundary points either way)."""
    a, b = edges(poly)
    x, y = p[..., 0, None], p[..., 1, None]
    crosses = (a[:, 1] > y) != (b[:, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xint = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return (np.count_nonzero(crosses & (x < xint), axis=-1) % 2) == 1


def signed_distance(p: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Distance of points ``p[..., 2]`` to the polygon's boundary, negative inside."""
    a, b = edges(poly)
    d = segment_distance(p, a, b).min(axis=-1)
    return np.where(inside(p, poly), -d, d)


def signed_distance_edgewise(p: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """:func:`signed_distance` for many points ``p[..., 2]``, one edge at a time: the same
    operations on the same numbers (so the same floats), in memory of a few copies of ``p``
    instead of ``p`` times the vertices (a grid window near a long polygon)."""
    px, py = p[..., 0], p[..., 1]
    best = np.full(px.shape, np.inf)
    odd = np.zeros(px.shape, dtype=bool)
    a, b = edges(poly)
    d = b - a
    n2 = np.maximum(np.einsum("mi,mi->m", d, d), 1e-300)
    for k in range(len(poly)):
        (ax, ay), (bx, by), (dx, dy) = a[k], b[k], d[k]
        u = np.clip(((px - ax) * dx + (py - ay) * dy) / n2[k], 0.0, 1.0)
        ex, ey = px - (ax + u * dx), py - (ay + u * dy)
        np.minimum(best, np.sqrt(ex * ex + ey * ey), out=best)
        crosses = (ay > py) != (by > py)
        with np.errstate(divide="ignore", invalid="ignore"):
            xint = ax + (py - ay) * (bx - ax) / (by - ay)
        odd ^= crosses & (px < xint)
    return np.where(odd, -best, best)


def area(poly: np.ndarray) -> float:
    """Signed area (> 0 counter-clockwise)."""
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _orient(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    return (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - \
        (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0])


def segments_cross(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Do segments a-b and c-d (broadcast) properly cross or touch?"""
    o1, o2 = _orient(a, b, c), _orient(a, b, d)
    o3, o4 = _orient(c, d, a), _orient(c, d, b)
    proper = (o1 * o2 < 0) & (o3 * o4 < 0)
    return proper | ((o1 == 0) & _on(a, b, c)) | ((o2 == 0) & _on(a, b, d)) | \
        ((o3 == 0) & _on(c, d, a)) | ((o4 == 0) & _on(c, d, b))


def _on(a: np.ndarray, b: np.ndarray, p: np.ndarray) -> np.ndarray:
    return (np.minimum(a[..., 0], b[..., 0]) <= p[..., 0]) & \
        (p[..., 0] <= np.maximum(a[..., 0], b[..., 0])) & \
        (np.minimum(a[..., 1], b[..., 1]) <= p[..., 1]) & \
        (p[..., 1] <= np.maximum(a[..., 1], b[..., 1]))


def simple_polygon_problem(poly: np.ndarray) -> str | None:
    """Why ``poly`` is not a simple polygon (too few vertices, repeated vertex, zero area,
    crossing edges), or None."""
    n = len(poly)
    if n < 3:
        return "a polygon needs at least 3 vertices"
    a, b = edges(poly)
    if np.any(np.linalg.norm(b - a, axis=1) == 0):
        return "a polygon may not repeat a vertex"
    if abs(area(poly)) < 1e-9:
        return "the polygon has no area"
    i, j = np.triu_indices(n, 2)
    keep = ~((i == 0) & (j == n - 1))  # the first and last edges share a vertex
    i, j = i[keep], j[keep]
    if np.any(segments_cross(a[i], b[i], a[j], b[j])):
        return "the polygon's edges cross (expected a simple polygon)"
    return None
