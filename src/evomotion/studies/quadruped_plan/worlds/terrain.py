"""The planner's view of a world: distance grids and conservative move checks.

Two signed-distance grids (node spacing ``grid``) are computed once from the exact polygon
distances (:mod:`.geometry`): to the obstacles (and the bounds) for the body and legs, and to
the no-step zones, obstacles and bounds for the feet. A value read at the nearest node is off
by at most ``grid / sqrt 2``, so the tests below are conservative:

* a foot is placed only where the true distance to every no-step zone and obstacle is
  >= ``foot_clearance``;
* the body rectangle keeps >= ``body_clearance`` from every obstacle at every instant of a
  body move (poses sampled so that no point of the body moves more than ``SPACING`` between
  samples, the outline sampled every ``SPACING``, and the sampling error added to the
  threshold), and no obstacle vertex lies inside the body.

Obstacles bound the *body*: a leg may reach over one as long as the foot lands outside it
(and outside the no-step zones) — obstacles are things a body cannot pass but a leg can
step over or round. Quick tests first: a rotation sweeps the disc of radius ``r_hip``
about the centre, a translation a chain of such discs; feet are checked one by one only when
the centre is within ``r_robot`` (hip radius + reach) of a no-step zone or obstacle. This
keeps the search near its obstacle-free speed.
"""

from __future__ import annotations

import copy
import functools
import math
from collections.abc import Iterable

import numpy as np

from evomotion.errors import FileFormatError, InputError
from evomotion.studies.quadruped_plan.rules.model import QuadrupedModel
from evomotion.studies.quadruped_plan.worlds.geometry import (
    signed_distance,
    signed_distance_edgewise,
)
from evomotion.studies.quadruped_plan.worlds.world import (
    GRID_REACH,
    MAX_GRID_NODES,
    Polygon,
    World,
    grid_nodes,
)

SPACING = 0.1  # [units] outline and pose sampling of the detailed checks
CAP = GRID_REACH  # [units] distances are exact up to CAP (enough for the quick tests)
QUICK_STEP = 0.5  # [units] disc spacing of the quick translation test


class Terrain:
    """A world as the planner knows it: ``known`` obstacles (default: all but hidden)."""

    def __init__(self, world: World, model: QuadrupedModel,
                 known: Iterable[Polygon] | None = None, body_clearance: float = 0.05,
                 foot_clearance: float = 0.05, grid: float = 0.1) -> None:
        self.world, self.model = world, model
        self.body_clearance, self.foot_clearance, self.grid = body_clearance, foot_clearance, grid
        self.obstacles = list(world.of_kind("obstacle") if known is None else known)
        x0, y0, x1, y1 = world.bounds
        self.x0, self.y0, self.inv = x0, y0, 1.0 / grid
        self.nx, self.ny = grid_nodes(world.bounds, grid)
        if not grid > 0 or self.nx * self.ny > MAX_GRID_NODES:  # before any allocation
            raise InputError(f"{world.source or world.name}: expected a world of at most "
                             f"{MAX_GRID_NODES:,} grid nodes of {grid:g} units, got "
                             f"{x1 - x0:.6g} x {y1 - y0:.6g} units")
        gx = x0 + grid * np.arange(self.nx)
        gy = y0 + grid * np.arange(self.ny)
        self._nodes = np.stack(np.meshgrid(gx, gy, indexing="ij"), axis=-1)
        inner = np.minimum(np.minimum(self._nodes[..., 0] - x0, x1 - self._nodes[..., 0]),
                           np.minimum(self._nodes[..., 1] - y0, y1 - self._nodes[..., 1]))
        self.body_sdf = np.minimum(inner, CAP)
        for p in self.obstacles:
            self._carve(self.body_sdf, p.points)
        self.foot_sdf = self.body_sdf.copy()
        for p in world.of_kind("nostep"):
            self._carve(self.foot_sdf, p.points)
        err = grid * math.sqrt(0.5)
        self.body_thr = body_clearance + err + SPACING
        self.foot_thr = foot_clearance + err
        hips = np.array(model.hips)
        self.r_hip = float(np.max(np.hypot(hips[:, 0], hips[:, 1])))
        self.r_robot = self.r_hip + model.l_max
        self._refresh()

    def _carve(self, sdf: np.ndarray, poly: np.ndarray) -> None:
        lo = np.floor((poly.min(axis=0) - CAP - [self.x0, self.y0]) * self.inv).astype(int)
        hi = np.ceil((poly.max(axis=0) + CAP - [self.x0, self.y0]) * self.inv).astype(int) + 1
        i0, j0 = max(lo[0], 0), max(lo[1], 0)
        i1, j1 = min(hi[0], self.nx), min(hi[1], self.ny)
        if i0 >= i1 or j0 >= j1:
            return
        window = self._nodes[i0:i1, j0:j1]
        sdf[i0:i1, j0:j1] = np.minimum(sdf[i0:i1, j0:j1], signed_distance_edgewise(window, poly))

    def _refresh(self) -> None:
        self._body_flat = self.body_sdf.ravel()
        self._body_rows = self.body_sdf.tolist()
        self._foot_rows = self.foot_sdf.tolist()
        verts = [p.points for p in self.obstacles]
        self._verts = np.vstack(verts).astype(float) if verts else np.zeros((0, 2))

    def with_obstacles(self, extra: Iterable[Polygon]) -> Terrain:
        """A copy that also knows the obstacles ``extra`` (only they are carved: the grids
        are minima of per-polygon distances, so the result equals a terrain built with all
        of them, bit for bit)."""
        out = copy.copy(self)
        out.obstacles = [*self.obstacles, *extra]
        out.body_sdf, out.foot_sdf = self.body_sdf.copy(), self.foot_sdf.copy()
        for p in out.obstacles[len(self.obstacles):]:
            out._carve(out.body_sdf, p.points)
            out._carve(out.foot_sdf, p.points)
        out._refresh()
        return out

    # -- scalar reads ---------------------------------------------------------------------
    def body_distance(self, x: float, y: float) -> float:
        i, j = int((x - self.x0) * self.inv + 0.5), int((y - self.y0) * self.inv + 0.5)
        return self._body_rows[i][j] if 0 <= i < self.nx and 0 <= j < self.ny else -1.0

    def foot_ok(self, x: float, y: float) -> bool:
        i, j = int((x - self.x0) * self.inv + 0.5), int((y - self.y0) * self.inv + 0.5)
        return 0 <= i < self.nx and 0 <= j < self.ny and self._foot_rows[i][j] >= self.foot_thr

    def feet_open(self, x: float, y: float) -> bool:
        """Can every foot of a robot centred at (x, y) go anywhere in its sector?"""
        i, j = int((x - self.x0) * self.inv + 0.5), int((y - self.y0) * self.inv + 0.5)
        return 0 <= i < self.nx and 0 <= j < self.ny and \
            self._foot_rows[i][j] >= self.r_robot + self.foot_thr

    # -- the body's outline -----------------------------------------------------------------
    @functools.cached_property
    def _outline_local(self) -> np.ndarray:
        """Sample points of the body rectangle's outline in the body frame ``[k, 2]``."""
        m = self.model
        a2, b2 = m.a / 2, m.b / 2
        corners = np.array([[-a2, b2], [-a2, -b2], [a2, -b2], [a2, b2]])
        rect = []
        for k in range(4):
            p, q = corners[k], corners[(k + 1) % 4]
            t = np.linspace(0, 1, max(2, int(np.ceil(np.hypot(*(q - p)) / SPACING)) + 1))
            rect.append(p + t[:, None] * (q - p))
        return np.vstack(rect)

    def _no_vertex_inside(self, poses: np.ndarray, c: np.ndarray | None = None,
                          s: np.ndarray | None = None) -> bool:
        if not len(self._verts):
            return True
        d = self._verts[None, :, :] - poses[:, None, :2]
        if c is None or s is None:
            c, s = _cos_sin(poses[:, 2])
        u, v = c * d[..., 0] + s * d[..., 1], -s * d[..., 0] + c * d[..., 1]
        return not np.any((np.abs(u) < self.model.a / 2) & (np.abs(v) < self.model.b / 2))

    def _sweep_clear(self, poses: np.ndarray) -> bool:
        """The body's outline at every pose ``[n, 3]`` clear of obstacles (the body grid at
        the nearest node of each outline sample, at least ``body_thr``) and no obstacle
        vertex inside the body (the hot path of the walker's searches)."""
        local = self._outline_local
        c, s = _cos_sin(poses[:, 2])
        lx, ly = local[:, 0], local[:, 1]
        i = np.rint((poses[:, 0:1] + (c * lx - s * ly) - self.x0) * self.inv)
        j = np.rint((poses[:, 1:2] + (s * lx + c * ly) - self.y0) * self.inv)
        if i.min() < 0 or j.min() < 0 or i.max() >= self.nx or j.max() >= self.ny:
            return False
        flat = (i * self.ny + j).astype(np.int64)
        if not (self._body_flat[flat] >= self.body_thr).all():
            return False
        return self._no_vertex_inside(poses, c, s)

    # -- move checks (state = (x, y, phi, 8 body-frame feet, ...)) ------------------------
    @staticmethod
    def world_feet(s: tuple) -> np.ndarray:
        c, sn = math.cos(s[2]), math.sin(s[2])
        return np.array([[s[0] + c * s[3 + 2 * i] - sn * s[4 + 2 * i],
                          s[1] + sn * s[3 + 2 * i] + c * s[4 + 2 * i]] for i in range(4)])

    def rotation_ok(self, s: tuple, turn: float) -> bool:
        """May the body turn by ``turn`` [rad] about its centre? (It sweeps a disc.)"""
        if self.body_distance(s[0], s[1]) >= self.r_hip + self.body_thr:
            return True
        n = int(math.ceil(abs(turn) * self.r_hip / SPACING)) + 1
        phis = s[2] + np.linspace(0.0, turn, n)
        return self._sweep_clear(np.stack([np.full(n, s[0]), np.full(n, s[1]), phis], axis=1))

    def translation_ok(self, s: tuple, nx: float, ny: float) -> bool:
        """May the body translate from its centre to (nx, ny)?"""
        d = math.hypot(nx - s[0], ny - s[1])
        k = int(math.ceil(d / QUICK_STEP))
        kk = max(k, 1)
        r = self.r_hip + 0.5 * d / kk + self.body_thr
        # quick test: discs along the way clear (body_distance inlined: the hot path)
        x, y, dx, dy = s[0], s[1], nx - s[0], ny - s[1]
        x0, y0, inv, nxg, nyg, rows = self.x0, self.y0, self.inv, self.nx, self.ny, \
            self._body_rows
        for i in range(k + 1):
            gi = int((x + dx * i / kk - x0) * inv + 0.5)
            gj = int((y + dy * i / kk - y0) * inv + 0.5)
            if not (0 <= gi < nxg and 0 <= gj < nyg) or rows[gi][gj] < r:
                break
        else:
            return True
        n = int(math.ceil(d / SPACING)) + 1
        t = np.linspace(0.0, 1.0, n)
        return self._sweep_clear(np.stack([s[0] + t * (nx - s[0]), s[1] + t * (ny - s[1]),
                                           np.full(n, s[2])], 1))

    def stance_problem(self, s: tuple) -> str | None:
        """Why the robot cannot stand in state ``s``, or None."""
        for k, (fx, fy) in enumerate(self.world_feet(s)):
            if not self.foot_ok(fx, fy):
                return f"foot {k} at ({fx:.2f}, {fy:.2f}) is in or near a no-step zone or " \
                       "obstacle"
        if not self._sweep_clear(np.array([s[:3]], dtype=float)):
            return "the body is in or near an obstacle"
        return None


def stand_problem(world: World, model: QuadrupedModel, point: tuple[float, float],
                  tol: float = 0.0, body_clearance: float = 0.05,
                  foot_clearance: float = 0.05) -> str | None:
    """Why the robot cannot stand anywhere within ``tol`` of ``point`` (a start or a goal),
    or None. Exact polygon distances, every obstacle (hidden ones too): the body rectangle
    holds the disc of radius ``min(a, b) / 2`` about its centre, so the centre needs that
    much room (plus ``body_clearance`` from obstacles), and every foot lies within
    hip radius + ``l_max`` of the centre, so a point that deep in no-step zones or obstacles
    leaves no foothold. Distances change by at most the distance moved, so no point of the
    tolerance disc can do better than the point itself plus ``tol``: a refusal is certain."""
    p = np.array(point, dtype=float)
    x0, y0, x1, y1 = world.bounds
    edge = min(p[0] - x0, x1 - p[0], p[1] - y0, y1 - p[1])
    half = min(model.a, model.b) / 2
    obstacles = [float(signed_distance(p, q.points)) for q in world.of_kind("obstacle", "hidden")]
    nearest = min(obstacles, default=math.inf)
    if edge + tol < half:
        return f"the body ({model.a:g} x {model.b:g}) does not fit inside the bounds there"
    if nearest + tol < half + body_clearance:
        where = "inside an obstacle" if nearest < 0 else f"{nearest:.3g} units from an obstacle"
        return (f"the body ({model.a:g} x {model.b:g}) cannot stand within {tol:g} of it: "
                f"the point is {where}, the body needs {half + body_clearance:g}")
    hips = np.array(model.hips)
    reach = float(np.max(np.hypot(hips[:, 0], hips[:, 1]))) + model.l_max
    feet = [float(signed_distance(p, q.points)) for q in world.of_kind("nostep")]
    if min(feet, default=math.inf) + reach + tol < foot_clearance:
        return f"every foothold within reach ({reach:.3g} units) is in a no-step zone"
    return None


def check_world_task(world: World, model: QuadrupedModel, body_clearance: float,
                     foot_clearance: float) -> None:
    """A start or a goal where the robot cannot stand is an error on its line of the world
    file, before any grid is built or any search runs (a goal inside an obstacle would
    otherwise search to the end of the budget)."""
    for key, point, tol, line in (("start", world.start[:2], 0.0, world.start_line),
                                  ("goal", world.goal, world.goal_tolerance, world.goal_line)):
        why = stand_problem(world, model, point, tol, body_clearance, foot_clearance)
        if why is not None:
            raise FileFormatError(world.source, line, f"{key}: the robot cannot stand "
                                  f"there ({why})")


def _cos_sin(phis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Columns ``[n, 1]`` of cos and sin of ``phis`` by the C library (``math``), as the
    compiled successors (_walkcore.c) take them."""
    return (np.array([math.cos(p) for p in phis])[:, None],
            np.array([math.sin(p) for p in phis])[:, None])
