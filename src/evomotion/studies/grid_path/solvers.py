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

import math
from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any

import numpy as np

from evomotion.core.search import best_first
from evomotion.studies.grid_path.geometry import segments_valid
from evomotion.studies.grid_path.maps import GridMap, octile_moves

SQRT2 = math.sqrt(2.0)
MODELS = ("octile", "centres", "free")
UNBOUNDED = 1 << 62  # no expansion budget: the exact searches run to the goal


@dataclass(frozen=True)
class Solution:
    """An exact optimum: ``length`` and the polyline ``waypoints[k, 2]`` (cell units)."""

    model: str
    length: float
    waypoints: np.ndarray
    n_straight: int = -1  # octile only: exact length = n_straight + n_diagonal * sqrt(2)
    n_diagonal: int = -1


class _OctileGrid:
    """The 8-connected grid for the core search: a state is ``(x, y, n_straight, n_diagonal)``
    (the length kept exact), its duplicate key the cell ``(x, y)``."""

    def __init__(self, m: GridMap) -> None:
        self.m = m

    def start(self) -> tuple[int, int, int, int]:
        return (*self.m.start, 0, 0)

    def is_goal(self, s: tuple) -> bool:
        return (s[0], s[1]) == self.m.goal

    def key(self, s: tuple) -> tuple[int, int]:
        return s[0], s[1]

    def successors(self, s: tuple) -> list[tuple[bool, tuple, float]]:
        x0, y0, ns, nd = s
        return [(diag, (x, y, ns, nd + 1) if diag else (x, y, ns + 1, nd), SQRT2 if diag else 1.0)
                for x, y, diag in octile_moves(self.m.blocked, x0, y0)]


def _exact_g_then_cell(goal: bool, g: float, key: Hashable, s: Any) -> tuple:
    """Ties of f: the shorter exact length, then the cell (the search's order before the core
    search took it over)."""
    return s[2] + s[3] * SQRT2, key


def octile_astar(m: GridMap) -> Solution:
    """Exact octile shortest path between the start and goal cell centres (A* of the core
    search; f = exact length + octile distance, a consistent heuristic, so nothing re-opens)."""
    gx, gy = m.goal

    def evaluate(pf: Any, pg: Any, ps: Any, s: tuple, rule: Any, step_cost: float) -> float:
        dx, dy = abs(s[0] - gx), abs(s[1] - gy)
        return (s[2] + s[3] * SQRT2) + ((SQRT2 - 1.0) * min(dx, dy) + max(dx, dy))

    res = best_first(_OctileGrid(m), evaluate, max_expansions=UNBOUNDED,
                     min_improvement=1e-12, tie_break=_exact_g_then_cell)
    if not res.found:
        raise ValueError(f"{m.name}: goal unreachable")
    _, _, ns, nd = res.states[-1]
    pts = np.array([s[:2] for s in res.states], dtype=float) + 0.5
    return Solution("octile", ns + nd * SQRT2, pts, ns, nd)


class _Visibility:
    """Straight valid segments between ``nodes`` for the core search, tested lazily: when
    ``u`` is expanded, only the segments that improve a tentative distance and can still beat
    ``ub`` and the goal's tentative distance are tested, in one vectorised batch. It keeps its
    own copy of the tentative distances ``g`` (the search accepts every edge it returns)."""

    def __init__(self, blocked: np.ndarray, nodes: np.ndarray, s: int, t: int, rule: str,
                 ub: float) -> None:
        self.blocked, self.nodes, self.s, self.t, self.rule = blocked, nodes, s, t, rule
        n = nodes.shape[0]
        self.h = np.hypot(*(nodes - nodes[t]).T)
        self.g = np.full(n, np.inf)
        self.g[s] = 0.0
        self.done = np.zeros(n, dtype=bool)
        self.ub = ub + 1e-9

    def start(self) -> int:
        return self.s

    def is_goal(self, u: int) -> bool:
        return u == self.t

    def key(self, u: int) -> int:
        return u

    def successors(self, u: int) -> list[tuple[None, int, float]]:
        nodes, g, h, done = self.nodes, self.g, self.h, self.done
        done[u] = True
        d = np.hypot(*(nodes - nodes[u]).T)
        cand = ~done & (g[u] + d < g - 1e-12) & (g[u] + d + h <= min(self.ub, g[self.t]))
        idx = np.flatnonzero(cand)
        if idx.size == 0:
            return []
        ok = segments_valid(self.blocked, np.repeat(nodes[u:u + 1], idx.size, 0), nodes[idx],
                            self.rule)
        out = []
        for v in idx[ok].tolist():
            g[v] = g[u] + d[v]
            out.append((None, v, d[v]))
        return out


def visibility_astar(blocked: np.ndarray, nodes: np.ndarray, s: int, t: int, rule: str,
                     ub: float = math.inf) -> tuple[float, list[int]]:
    """Exact shortest path from node ``s`` to node ``t`` over straight valid segments (A* of
    the core search, h = straight-line distance; ties of f go to the lower node index)."""
    space = _Visibility(blocked, nodes, s, t, rule, ub)
    h = space.h

    def evaluate(pf: Any, pg: Any, ps: Any, v: int, rule: Any, step_cost: float) -> float:
        return (0.0 if pg is None else pg + step_cost) + h[v]

    res = best_first(space, evaluate, max_expansions=UNBOUNDED,
                     min_improvement=-math.inf, tie_break=_node_index)
    if not res.found:
        raise ValueError("goal unreachable")
    return float(space.g[t]), res.states


def _node_index(goal: bool, g: float, key: Hashable, s: Any) -> Hashable:
    return key


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
