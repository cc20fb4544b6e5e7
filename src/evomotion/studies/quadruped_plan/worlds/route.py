"""The global route of the receding-horizon walker: where to head next.

The paper's rules always steer at "the goal" (rule 1 turns towards it, rule 3 stops at its
projection), so a robot that must walk round an obstacle needs intermediate goals. The route
is a shortest path for the body centre on an 8-connected grid (``ROUTE_GRID`` units) over the
cells where the body-obstacle distance (:class:`.terrain.Terrain`) is at least
``clearance`` (default: the hip radius plus 0.75, so the body can turn there), each step
costing its length times ``1 + PROXIMITY * max(0, comfort - distance)`` so that the route
keeps to the middle of passages (scipy's Dijkstra from the goal, recomputed only when the
world changes: an obstacle comes into view or the goal moves). The walker's sub-goal is the
farthest route point within ``lookahead`` units that it can walk to in a straight line with
``line_clearance`` (hip radius + 0.5) to spare, so that it can turn on the way.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from evomotion.studies.quadruped_plan.worlds.terrain import Terrain

ROUTE_GRID = 0.5  # [units]
PROXIMITY = 1.0  # extra cost per unit of missing comfort distance


class Route:
    """Cost-to-go to ``goal`` over the free cells of ``terrain``."""

    def __init__(self, terrain: Terrain, goal: tuple[float, float],
                 clearance: float | None = None) -> None:
        self.terrain, self.goal = terrain, goal
        x0, y0, x1, y1 = terrain.world.bounds
        self.x0, self.y0 = x0, y0
        self.nx = int(math.floor((x1 - x0) / ROUTE_GRID)) + 1
        self.ny = int(math.floor((y1 - y0) / ROUTE_GRID)) + 1
        step = max(1, int(round(ROUTE_GRID / terrain.grid)))
        dist = terrain.body_sdf[::step, ::step][: self.nx, : self.ny]
        self.nx, self.ny = dist.shape
        self.clearance = terrain.r_hip + 0.75 if clearance is None else clearance
        self.line_clearance = terrain.r_hip + 0.5
        comfort = terrain.r_robot + 1.0
        free = dist >= self.clearance
        penalty = 1.0 + PROXIMITY * np.maximum(0.0, comfort - dist)
        idx = np.arange(self.nx * self.ny).reshape(self.nx, self.ny)
        ii, jj = np.meshgrid(np.arange(self.nx), np.arange(self.ny), indexing="ij")
        rows, cols, w = [], [], []
        for di, dj in ((1, 0), (0, 1), (1, 1), (1, -1)):
            i2, j2 = ii + di, jj + dj
            inb = (i2 < self.nx) & (j2 >= 0) & (j2 < self.ny)
            a, b = idx[ii[inb], jj[inb]], idx[i2[inb], j2[inb]]
            ok = free.ravel()[a] & free.ravel()[b]
            cost = 0.5 * (penalty.ravel()[a] + penalty.ravel()[b]) * ROUTE_GRID * \
                math.hypot(di, dj)
            rows.append(a[ok])
            cols.append(b[ok])
            w.append(cost[ok])
        n = self.nx * self.ny
        graph = coo_matrix((np.concatenate(w), (np.concatenate(rows), np.concatenate(cols))),
                           shape=(n, n)).tocsr()
        self.goal_cell = self.cell(*goal)
        self.free = free
        self.cost, self.pred = dijkstra(graph, directed=False, indices=self.goal_cell,
                                        return_predecessors=True)

    def cell(self, x: float, y: float) -> int:
        i = min(max(int(round((x - self.x0) / ROUTE_GRID)), 0), self.nx - 1)
        j = min(max(int(round((y - self.y0) / ROUTE_GRID)), 0), self.ny - 1)
        return i * self.ny + j

    def _point(self, cell: int) -> tuple[float, float]:
        i, j = divmod(int(cell), self.ny)
        return self.x0 + i * ROUTE_GRID, self.y0 + j * ROUTE_GRID

    def _start_cell(self, x: float, y: float) -> int | None:
        """The robot's cell, or the nearest reachable cell within 3 units."""
        c = self.cell(x, y)
        if math.isfinite(self.cost[c]):
            return c
        i0, j0 = divmod(c, self.ny)
        r = int(math.ceil(3.0 / ROUTE_GRID))
        best, best_d = None, math.inf
        for i in range(max(0, i0 - r), min(self.nx, i0 + r + 1)):
            for j in range(max(0, j0 - r), min(self.ny, j0 + r + 1)):
                k = i * self.ny + j
                d = math.hypot(i - i0, j - j0)
                if math.isfinite(self.cost[k]) and d < best_d:
                    best, best_d = k, d
        return best

    def path(self, x: float, y: float) -> list[tuple[float, float]] | None:
        """Route points from (x, y) to the goal, or None when no route exists."""
        c = self._start_cell(x, y)
        if c is None:
            return None
        pts = [(x, y)]
        while c != self.goal_cell and c >= 0:
            pts.append(self._point(c))
            c = int(self.pred[c])
        pts.append(self.goal)
        return pts

    def to_go(self, x: float, y: float) -> float:
        """How far (x, y) is from the goal along the route: the cost-to-go of the nearest
        reachable cell plus the distance to it; the straight distance without a route."""
        c = self._start_cell(x, y)
        if c is None:
            return math.hypot(self.goal[0] - x, self.goal[1] - y)
        px, py = self._point(c)
        return float(self.cost[c]) + math.hypot(px - x, py - y)

    def line_clear(self, x: float, y: float, px: float, py: float) -> bool:
        """Does the straight walk from (x, y) to (px, py) keep ``line_clearance``?"""
        d = math.hypot(px - x, py - y)
        n = int(math.ceil(d / ROUTE_GRID)) + 1
        dist = self.terrain.body_distance
        return all(dist(x + (px - x) * k / n, y + (py - y) * k / n) >= self.line_clearance
                   for k in range(1, n + 1))

    def subgoal(self, x: float, y: float, lookahead: float) -> tuple[float, float] | None:
        """The farthest route point at most ``lookahead`` units along the route that the
        robot can walk to in a straight line keeping ``line_clearance`` (so that it can still
        turn on the way), the goal when nearer; None without a route."""
        pts = self.path(x, y)
        if pts is None:
            return None
        run, best = 0.0, None
        for (ax, ay), (bx, by) in zip(pts, pts[1:]):
            seg = math.hypot(bx - ax, by - ay)
            u = 1.0 if run + seg <= lookahead or seg == 0 else (lookahead - run) / seg
            p = (ax + u * (bx - ax), ay + u * (by - ay))
            if not self.line_clear(x, y, *p):
                break
            best = p
            run += seg
            if run >= lookahead:
                break
        if best is None:  # not even the first route point is in line: head for it anyway
            best = pts[1] if len(pts) > 1 else self.goal
        return self.goal if math.hypot(best[0] - self.goal[0], best[1] - self.goal[1]) < 1e-9 \
            else best
