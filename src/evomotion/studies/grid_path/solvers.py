"""Exact shortest paths under the three distance models of the grid-path study.

- ``octile``: A* (Hart, Nilsson & Raphael 1968) over 8-connected moves between free cell
  centres, diagonal cost sqrt(2), no corner cutting (Moving AI convention). The length is
  kept exactly as ``n_straight + n_diagonal * sqrt(2)``.
- ``centres``: straight segments between free cell centres that touch no blocked cell
  (``"closed"`` rule); A* on the visibility graph of the free centres.
- ``free``: a point robot, blocked cells as closed squares whose interior may not be
  entered (``"open"`` rule). Shortest paths among polygons bend only at obstacle vertices
  (Lozano-Perez & Wesley 1979), here the lattice points where exactly one of the four
  incident cells is blocked or two diagonal ones are (pinch points); A* on the visibility
  graph of those corners plus start and goal.

The visibility-graph searches are lazy: when a node is expanded, only the segments that
could improve a tentative distance and still beat an upper bound ``ub`` (a longer model's
optimum: free <= centres <= octile) are tested, in one vectorised batch.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

from evomotion.studies.grid_path.geometry import segments_valid
from evomotion.studies.grid_path.maps import GridMap, octile_moves

SQRT2 = math.sqrt(2.0)
MODELS = ("octile", "centres", "free")


@dataclass(frozen=True)
class Solution:
    """An exact optimum: ``length`` and the polyline ``waypoints[k, 2]`` (cell units)."""

    model: str
    length: float
    waypoints: np.ndarray
    n_straight: int = -1  # octile only: exact length = n_straight + n_diagonal * sqrt(2)
    n_diagonal: int = -1


def octile_astar(m: GridMap) -> Solution:
    """Exact octile shortest path between the start and goal cell centres."""
    gx, gy = m.goal

    def h(x: int, y: int) -> float:
        dx, dy = abs(x - gx), abs(y - gy)
        return (SQRT2 - 1.0) * min(dx, dy) + max(dx, dy)

    best: dict[tuple[int, int], tuple[int, int]] = {m.start: (0, 0)}  # (straight, diagonal)
    parent: dict[tuple[int, int], tuple[int, int]] = {}
    heap = [(h(*m.start), 0.0, m.start)]
    closed: set[tuple[int, int]] = set()
    while heap:
        _, g, node = heapq.heappop(heap)
        if node in closed:
            continue
        closed.add(node)
        if node == m.goal:
            break
        ns, nd = best[node]
        for x, y, diag in octile_moves(m.blocked, *node):
            cand = (ns, nd + 1) if diag else (ns + 1, nd)
            cg = cand[0] + cand[1] * SQRT2
            old = best.get((x, y))
            if old is None or cg < old[0] + old[1] * SQRT2 - 1e-12:
                best[(x, y)], parent[(x, y)] = cand, node
                heapq.heappush(heap, (cg + h(x, y), cg, (x, y)))
    if m.goal not in closed:
        raise ValueError(f"{m.name}: goal unreachable")
    path = [m.goal]
    while path[-1] != m.start:
        path.append(parent[path[-1]])
    ns, nd = best[m.goal]
    pts = np.array(path[::-1], dtype=float) + 0.5
    return Solution("octile", ns + nd * SQRT2, pts, ns, nd)


def visibility_astar(blocked: np.ndarray, nodes: np.ndarray, s: int, t: int, rule: str,
                     ub: float = math.inf) -> tuple[float, list[int]]:
    """Exact shortest path from node ``s`` to node ``t`` over straight valid segments."""
    n = nodes.shape[0]
    h = np.hypot(*(nodes - nodes[t]).T)
    g = np.full(n, np.inf)
    g[s] = 0.0
    parent = np.full(n, -1)
    done = np.zeros(n, dtype=bool)
    ub = ub + 1e-9
    heap = [(h[s], s)]
    while heap:
        _, u = heapq.heappop(heap)
        if done[u]:
            continue
        done[u] = True
        if u == t:
            break
        d = np.hypot(*(nodes - nodes[u]).T)
        cand = ~done & (g[u] + d < g - 1e-12) & (g[u] + d + h <= min(ub, g[t]))
        idx = np.flatnonzero(cand)
        if idx.size == 0:
            continue
        ok = segments_valid(blocked, np.repeat(nodes[u:u + 1], idx.size, 0), nodes[idx], rule)
        for v in idx[ok].tolist():
            g[v], parent[v] = g[u] + d[v], u
            heapq.heappush(heap, (g[v] + h[v], v))
    if not np.isfinite(g[t]):
        raise ValueError("goal unreachable")
    path = [t]
    while path[-1] != s:
        path.append(int(parent[path[-1]]))
    return float(g[t]), path[::-1]


def centres_optimum(m: GridMap, ub: float = math.inf) -> Solution:
    """Exact shortest path through free cell centres (closed-square visibility)."""
    ys, xs = np.nonzero(~m.blocked)
    nodes = np.stack([xs, ys], 1).astype(float) + 0.5
    index = {(int(x), int(y)): i for i, (x, y) in enumerate(zip(xs, ys, strict=True))}
    length, path = visibility_astar(m.blocked, nodes, index[m.start], index[m.goal], "closed",
                                    ub)
    return Solution("centres", length, nodes[path])


def obstacle_corners(blocked: np.ndarray) -> np.ndarray:
    """Lattice points ``[k, 2]`` where a taut free-space path may bend (see module doc)."""
    pad = np.pad(np.asarray(blocked, dtype=bool), 1, constant_values=True)
    sw, se, nw, ne = pad[:-1, :-1], pad[:-1, 1:], pad[1:, :-1], pad[1:, 1:]
    count = sw.astype(int) + se + nw + ne
    pinch = (count == 2) & (sw == ne)
    ys, xs = np.nonzero((count == 1) | pinch)
    return np.stack([xs, ys], 1).astype(float)


def free_optimum(m: GridMap, ub: float = math.inf) -> Solution:
    """Exact shortest free-space path (open-interior visibility over obstacle corners)."""
    nodes = np.concatenate([[m.start_xy, m.goal_xy], obstacle_corners(m.blocked)])
    length, path = visibility_astar(m.blocked, nodes, 0, 1, "open", ub)
    return Solution("free", length, nodes[path])


def all_optima(m: GridMap) -> dict[str, Solution]:
    """The three exact optima, each search bounded by the next longer model."""
    octile = octile_astar(m)
    centres = centres_optimum(m, octile.length)
    free = free_optimum(m, centres.length)
    return {"octile": octile, "centres": centres, "free": free}


def encoding_optimum(blocked: np.ndarray, start: np.ndarray, goal: np.ndarray,
                     layers: list[np.ndarray], rule: str) -> tuple[float, np.ndarray]:
    """Exact best path the discrete encoding can express: one point of each layer
    ``layers[i][k_i, 2]`` in order, by dynamic programming over consecutive layers."""
    prev = np.asarray(start, dtype=float)[None]
    cost = np.zeros(1)
    back: list[np.ndarray] = []
    for layer in [*layers, np.asarray(goal, dtype=float)[None]]:
        a = np.repeat(prev, len(layer), 0)
        b = np.tile(layer, (len(prev), 1))
        ok = segments_valid(blocked, a, b, rule).reshape(len(prev), len(layer))
        d = np.hypot(*(a - b).T).reshape(len(prev), len(layer))
        tot = np.where(ok, cost[:, None] + d, np.inf)
        back.append(np.argmin(tot, axis=0))
        cost, prev = tot.min(axis=0), layer
    if not np.isfinite(cost[0]):
        return math.inf, np.zeros((0, 2))
    k, pts = 0, [np.asarray(goal, float)]
    all_layers = [np.asarray(start, float)[None], *layers]
    for i in range(len(back) - 1, -1, -1):
        k = int(back[i][k])
        pts.append(all_layers[i][k])
    return float(cost[0]), np.array(pts[::-1])
