"""Obstacle-aware distance via a precomputed visibility graph.

Paper 001 (section 3.3) measured the finger-to-target distance also as the length of the way
around the obstacles but found it too slow. Here the graph over obstacle vertices and targets
is built once: an edge joins two nodes that see each other (no proper crossing of an obstacle
edge and the midpoint outside every closed obstacle), and Dijkstra gives ``node_to_target``.
A tip ``p`` then costs ``min(|p - t| if visible, min_v |p - v| + node_to_target[v, t])`` over
visible vertices ``v``: one vectorized visibility test per (tip, node) pair per evaluation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import csgraph

from evomotion.studies.arm_ik.geometry import points_in_polygons, proper_crossings
from evomotion.studies.arm_ik.scenario import Scenario


def _visible(a: np.ndarray, b: np.ndarray, edges: np.ndarray,
             closed: list[np.ndarray]) -> np.ndarray:
    """Pairwise visibility of points ``a[..., 2]`` and ``b[..., 2]`` (broadcast)."""
    a, b = np.broadcast_arrays(a, b)
    if edges.shape[0] == 0:
        return np.ones(a.shape[:-1], dtype=bool)
    seg = np.stack([a, b], axis=-2)[..., None, :, :]
    cross = np.asarray(proper_crossings(seg, edges).any(axis=-1))  # an array, not a scalar
    if closed:
        cross |= points_in_polygons((a + b) / 2, closed)
    return ~cross


@dataclass(frozen=True)
class VisibilityGraph:
    """Obstacle vertices, targets and the shortest way from each vertex to each target."""

    vertices: np.ndarray  # (V, 2)
    targets: np.ndarray  # (T, 2)
    node_to_target: np.ndarray  # (V, T) shortest path lengths (inf when cut off)
    edges: np.ndarray  # (M, 2, 2)
    closed: tuple[np.ndarray, ...]

    @classmethod
    def build(cls, scn: Scenario) -> VisibilityGraph:
        verts = np.unique(np.concatenate([p for p in scn.obstacles]), axis=0) \
            if scn.obstacles else np.zeros((0, 2))
        closed = [p for p in scn.obstacles if p.shape[0] > 3 and np.array_equal(p[0], p[-1])]
        edges = scn.obstacle_segments()
        nodes = np.concatenate([verts, scn.targets])
        vis = _visible(nodes[:, None], nodes[None], edges, closed)
        w = np.linalg.norm(nodes[:, None] - nodes[None], axis=-1)
        w = np.where(vis, w, 0.0)
        np.fill_diagonal(w, 0.0)
        dist = csgraph.shortest_path(w, method="D", directed=False)
        v = verts.shape[0]
        return cls(verts, scn.targets.copy(), dist[:v, v:], edges, tuple(closed))

    def distances(self, pts: np.ndarray) -> np.ndarray:
        """Way around the obstacles from points ``pts[n, F, 2]`` to every target: ``(n, F, T)``."""
        direct = np.linalg.norm(pts[..., None, :] - self.targets, axis=-1)
        out = np.where(_visible(pts[..., None, :], self.targets, self.edges, list(self.closed)),
                       direct, np.inf)
        if self.vertices.shape[0]:
            to_v = np.linalg.norm(pts[..., None, :] - self.vertices, axis=-1)  # (n, F, V)
            see = _visible(pts[..., None, :], self.vertices, self.edges, list(self.closed))
            to_v = np.where(see, to_v, np.inf)
            via = (to_v[..., :, None] + self.node_to_target).min(axis=-2)  # (n, F, T)
            out = np.minimum(out, via)
        return out
