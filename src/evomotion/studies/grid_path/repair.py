"""Repair that closes the gap between an evolved path and the free-space optimum.

The paper's encoding puts exactly one waypoint on each perpendicular, so its paths cannot
bend exactly at obstacle corners, where free-space shortest paths bend (Lozano-Perez &
Wesley 1979). The repair keeps the path's corridor and makes it taut:

1. nodes: the path's own waypoints plus every obstacle corner (see
   :func:`~.solvers.obstacle_corners`) within ``radius`` cells of the path;
2. the shortest path from S to G over straight valid segments between those nodes
   (``"open"`` rule) by the lazy visibility A* of :mod:`.solvers`.

Because consecutive waypoints of a valid input are joined by valid segments, the result is
never longer than the input; waypoints that became redundant are dropped (the A* skips
them) and the others slide onto obstacle corners. With a radius of a few cells this is the
exact free optimum whenever that optimum lies in the path's corridor.
"""

from __future__ import annotations

import numpy as np

from evomotion.studies.grid_path.geometry import polyline_segments_valid
from evomotion.studies.grid_path.solvers import obstacle_corners, visibility_astar


def point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance ``[P, S]`` from points ``p[P, 2]`` to segments ``a[S, 2] -> b[S, 2]``."""
    ab = b - a
    L2 = np.maximum((ab ** 2).sum(1), 1e-300)
    t = np.clip(((p[:, None, :] - a[None]) * ab[None]).sum(-1) / L2, 0.0, 1.0)
    q = a[None] + t[..., None] * ab[None]
    return np.hypot(*np.moveaxis(p[:, None, :] - q, -1, 0))


def taut_path(blocked: np.ndarray, waypoints: np.ndarray, radius: float = 2.0) -> np.ndarray:
    """The shortest open-rule path in the corridor of ``waypoints[k, 2]`` (S first, G last).

    Invalid input segments are simply not edges of the search, so an invalid input becomes
    valid when its corridor holds a valid route; otherwise it is returned unchanged.
    """
    pts = np.asarray(waypoints, dtype=float)
    corners = obstacle_corners(blocked)
    if corners.size:
        near = point_segment_distance(corners, pts[:-1], pts[1:]).min(axis=1) <= radius
        corners = corners[near]
    nodes = np.concatenate([pts[:1], pts[-1:], pts[1:-1], corners])
    try:
        _, path = visibility_astar(blocked, nodes, 0, 1, "open")
    except ValueError:
        return pts
    return nodes[path]


def repair_population(blocked: np.ndarray, polylines: np.ndarray, cost: np.ndarray,
                      k: int = 10, radius: float = 2.0, iterations: int = 4,
                      ) -> tuple[np.ndarray, float]:
    """Repair the ``k`` best distinct polylines (invalid ones too: the corridor search
    routes around their invalid segments); the shortest valid result and its length, or
    the best input unchanged when none becomes valid. Each repair is repeated (up to
    ``iterations`` times) in the corridor of its own result until it stops changing."""
    order = np.argsort(cost, kind="stable")
    seen: list[np.ndarray] = []
    best, best_len = None, np.inf
    for i in order.tolist():
        p = polylines[i]
        if any(np.allclose(p, q) for q in seen):
            continue
        seen.append(p)
        t = p
        for _ in range(iterations):  # the corridor follows the tightened path
            t_new = taut_path(blocked, t, radius)
            if len(t_new) == len(t) and np.allclose(t_new, t):
                break
            t = t_new
        if polyline_segments_valid(blocked, t[None], "open").all():
            length = float(np.hypot(*np.diff(t, axis=0).T).sum())
            if length < best_len:
                best, best_len = t, length
        if len(seen) >= k:
            break
    if best is None:
        i = int(order[0])
        return polylines[i], float(np.hypot(*np.diff(polylines[i], axis=0).T).sum())
    return best, best_len
