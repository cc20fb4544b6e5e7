"""Production rules of paper 003 (section 4) and the walking-plan search problem.

Rule set A (11 rules):
  1      rotate the body about its centre towards the goal heading, as far as the
         workspaces allow (stability is unchanged: the centre does not move);
  2      translate along the body Y axis by dY = b/3 in the walking sense;
  3      translate along the body Y axis in the walking sense by the largest possible dY
         (at most up to the goal's projection on the axis);
  4-7    set leg i = rule - 4 to its maximum length and maximum (rear) angle;
  8-11   set leg i = rule - 8 to mid length and nominal angle.
Rule set B (27 rules) adds, for leg i = (rule - 4) mod 4: 12-15 maximum length, 16-19
minimum length, 20-23 maximum working angle, 24-27 minimum working angle (the other polar
coordinate kept). The walking sense (``sense``) is body -Y by default; see the docs.

A leg may move only when the other three feet hold the body with a stability margin of at
least ``model.min_margin``. A rule that leaves the state unchanged is not applicable.
Rules 1-3 are body moves, rules 4-27 leg moves (the paper's ``step`` = 1). Beyond the paper,
``shifts=True`` adds the body shifts 28-31 of :mod:`.shifts` (for the receding-horizon
walker); 32 (step back, :mod:`.recovery`) is never searched, only executed.
"""

from __future__ import annotations

import math
import os
from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any

import numpy as np

from evomotion.studies.quadruped_plan.rules.model import (
    EPS,
    STABILITY_TOL,
    WORKSPACE_TOL,
    QuadrupedModel,
    rotation_limit,
    translation_limit,
)
from evomotion.studies.quadruped_plan.rules.shifts import shift_moves, shifted

try:  # the successors in C (setup.py builds it when a compiler is there); else Python
    import evomotion.studies.quadruped_plan.rules._walkcore as _walkcore
except ImportError:  # pragma: no cover - depends on the install
    _walkcore = None
if os.environ.get("EVOMOTION_PURE_PYTHON", "0") not in ("", "0"):  # the Python code only
    _walkcore = None

RULE_SETS = {"A": 11, "B": 27}
MIN_MOVE = 1e-4  # a body move shorter than this [units or rad] is not applicable
POS_GRID = 0.01  # default duplicate-detection grid for positions [units]
ANGLE_GRID = 0.001  # default duplicate-detection grid for the body angle [rad]
# The key packs the 11 grid indices into one int, field i = index i + 2**(KEY_BITS - 1)
# (injective while every |index| < 2**(KEY_BITS - 1), i.e. |coordinate| < 5e9 units): it
# hashes and compares faster than a tuple, and a leg move changes it by one addition.
KEY_BITS = 40
KEY_WEIGHT = tuple(1 << (KEY_BITS * i) for i in range(11))
KEY_OFFSET = sum(w << (KEY_BITS - 1) for w in KEY_WEIGHT)
TWO_PI = 2.0 * math.pi
OPTIONS_CACHE = 200_000  # memoised foot positions per leg (the cache is cleared when full)


def is_leg_rule(rule: int) -> bool:
    """Rules 4-27 move a leg; 1-3, the shifts 28-31 and the step back 32 move the body."""
    return 4 <= rule <= 27


def rule_leg(rule: int) -> int:
    """Leg index moved by a leg rule."""
    return (rule - 4) % 4


@dataclass(frozen=True)
class ExclusionZone:
    """A disc the body centre may not enter and no foot may be placed in."""

    x: float
    y: float
    radius: float

    def contains(self, px: float, py: float) -> bool:
        return math.hypot(px - self.x, py - self.y) < self.radius

    def hits_segment(self, ax: float, ay: float, bx: float, by: float) -> bool:
        dx, dy = bx - ax, by - ay
        n2 = dx * dx + dy * dy
        u = 0.0 if n2 == 0 else max(0.0, min(1.0, ((self.x - ax) * dx + (self.y - ay) * dy) / n2))
        return self.contains(ax + u * dx, ay + u * dy)


def heading_error(state: tuple[float, ...], goal: tuple[float, float], sense: int) -> float:
    """Signed rotation [rad] that points the walking direction at the goal.

    ``sense`` = +1: the walking direction is +Y of the body; -1: -Y; 0: whichever sense of
    the body Y axis is nearer the goal direction.
    """
    bearing = math.atan2(goal[1] - state[1], goal[0] - state[0])
    heading = state[2] - math.pi / 2 if sense < 0 else state[2] + math.pi / 2
    diff = (bearing - heading + math.pi) % (2 * math.pi) - math.pi
    if sense == 0 and abs(diff) > math.pi / 2:
        diff = diff - math.pi if diff > 0 else diff + math.pi
    return diff


class WalkProblem:
    """The state space of paper 003 as a :class:`evomotion.core.search.SearchProblem`.

    States are tuples ``(x, y, phi, p0x, p0y, ..., p3x, p3y)`` (see ``model``); every rule
    costs 1 (the plan length in transitions is the A* cost).
    """

    def __init__(self, model: QuadrupedModel, start: tuple[float, ...],
                 goal: tuple[float, float], rule_set: str = "A", goal_tolerance: float = 0.25,
                 sense: int = -1, zone: ExclusionZone | None = None,
                 pos_grid: float = POS_GRID, angle_grid: float = ANGLE_GRID,
                 terrain: Any = None, options_cache: list[dict] | None = None,
                 shifts: bool = False, compiled: bool = True) -> None:
        if rule_set not in RULE_SETS:
            raise ValueError(f"unknown rule set {rule_set!r}; available: A, B")
        self.model, self.goal, self.rule_set = model, goal, rule_set
        self.n_rules = RULE_SETS[rule_set]
        if sense not in (-1, 0, 1):
            raise ValueError(f"walking sense must be -1, 0 or +1, got {sense}")
        self.goal_tolerance, self.sense, self.zone = goal_tolerance, sense, zone
        self.terrain = terrain  # a :class:`.terrain.Terrain` (no-step zones, obstacles) or None
        if shifts and sense == 0:
            raise ValueError("body shifts need a walking sense of -1 or +1")
        self.shifts = shifts  # rules 28-31 (:mod:`.shifts`), beyond the paper
        self._shift_cache: dict = {}  # body-frame feet -> shifts (see ``options_cache``)
        if not (pos_grid > 0 and angle_grid > 0):
            raise ValueError("duplicate grids must be > 0")
        self.pos_grid, self.angle_grid = pos_grid, angle_grid
        self._q = 1.0 / pos_grid
        self._start = self._with_key(tuple(float(v) for v in start))
        mid = 0.5 * (model.l_min + model.l_max)
        self._hips = model.hips
        self._unit_max = [(math.cos(model.max_angle(i)), math.sin(model.max_angle(i)))
                          for i in range(4)]
        self._unit_min = [(math.cos(model.min_angle(i)), math.sin(model.min_angle(i)))
                          for i in range(4)]
        self._fixed = []  # (leg, rule, fx, fy) of rules 4-11 (index rule - 4), body frame
        for rule0, length, angle in ((4, model.l_max, model.max_angle),
                                     (8, mid, model.nominal_angle)):
            for leg in range(4):
                self._fixed.append((leg, rule0 + leg, *model.foot_at(leg, length, angle(leg))))
        # per leg: (rule, fx, fy, the foot's part of the key) of rules 4 + leg and 8 + leg
        self._fixed_keyed = [tuple((r, fx, fy, round(fx * self._q) * KEY_WEIGHT[3 + 2 * leg]
                                    + round(fy * self._q) * KEY_WEIGHT[4 + 2 * leg])
                                   for _, r, fx, fy in (self._fixed[leg], self._fixed[4 + leg]))
                             for leg in range(4)]
        self._stable = model.min_margin - STABILITY_TOL
        self.parts = (0, 1, 2) if self.n_rules == 27 else (0, 1)
        # per leg: foot position -> moves; they depend on the model, rule set and grid only, so
        # problems of the same robot (a receding-horizon walker's replans) may share it
        self._options: list[dict] = options_cache if options_cache is not None else \
            [{}, {}, {}, {}]
        if options_cache is not None:  # a fifth entry memoises the body shifts
            if len(options_cache) == 4:
                options_cache.append({})
            self._shift_cache = options_cache[4]
        self.core = False
        if compiled and _walkcore is not None and zone is None and not shifts:
            # the same successors from compiled code (_walkcore.c; tested equal)
            c = _walkcore.WalkCore(*self._core_args())
            # the compiled successors shadow the Python methods on this instance
            self.body_moves = c.body_moves  # type: ignore[method-assign]
            self.leg_options = c.leg_options  # type: ignore[method-assign]
            self.core = True

    def _core_args(self) -> tuple:
        """The constructor arguments of :class:`_walkcore.WalkCore` (see _walkcore.c)."""
        m = self.model
        numbers = [v for _, hx, hy, side in m._trans for v in (hx, hy, side)]
        for h, th, out_c, in_c, wedge in m._rot:
            numbers += [h, th, out_c, in_c, *wedge[0], *wedge[1]]
        numbers += [1.0 / math.tan(m.sector_half_width), m.l_max, m.l_min, m.b / 3, EPS,
                    WORKSPACE_TOL, MIN_MOVE, self._stable, m.l_max ** 2]
        problem = [self.goal[0], self.goal[1], self._q, self.angle_grid, self.sense,
                   1.0 if self.n_rules == 27 else 0.0]
        fixed = [v for leg in range(4) for k in (leg, 4 + leg) for v in self._fixed[k][2:]]
        units = [v for u in (self._unit_max, self._unit_min) for xy in u for v in xy]
        t = self.terrain
        terrain = None
        if t is not None:
            from evomotion.studies.quadruped_plan.worlds.terrain import QUICK_STEP, SPACING

            outline = np.ascontiguousarray(t._outline_local, dtype=float)
            terrain = (t, t.body_sdf, t.foot_sdf, t.x0, t.y0, t.inv, t.nx, t.ny, t.r_hip,
                       t.body_thr, t.foot_thr, t.r_robot, outline, len(outline),
                       t.model.a / 2, t.model.b / 2, SPACING, QUICK_STEP)
        return numbers, problem, fixed, units, terrain, KEY_OFFSET

    def _with_key(self, v: tuple[float, ...]) -> tuple:
        """The state tuple: the 11 floats followed by the duplicate key (see :meth:`key`)."""
        q = self._q
        key = round((v[2] % TWO_PI) / self.angle_grid) * KEY_WEIGHT[2] + KEY_OFFSET
        for i in (0, 1, 3, 4, 5, 6, 7, 8, 9, 10):
            key += round(v[i] * q) * KEY_WEIGHT[i]
        return (*v[:11], key)

    def make_state(self, values: tuple[float, ...]) -> tuple:
        """A state tuple (11 floats and the duplicate key) from the 11 values."""
        return self._with_key(tuple(float(v) for v in values[:11]))

    def start(self) -> tuple:
        return self._start

    def is_goal(self, s: tuple) -> bool:
        return math.hypot(self.goal[0] - s[0], self.goal[1] - s[1]) <= self.goal_tolerance

    def key(self, s: tuple) -> Hashable:
        """Duplicates: body x, y and feet (body frame) on a ``pos_grid`` grid, phi (mod 2 pi)
        on an ``angle_grid`` grid (defaults POS_GRID, ANGLE_GRID); the 11 grid indices packed
        into one int (``KEY_BITS`` each)."""
        return s[11]

    def successors(self, s: tuple) -> list[tuple[int, tuple, float]]:
        out = self.body_moves(s)
        self._leg_moves(s, out)
        return out

    # -- body moves -------------------------------------------------------------------------
    def _translate(self, s: tuple, dist: float) -> tuple | None:
        c, sn = math.cos(s[2]), math.sin(s[2])
        nx, ny = s[0] - sn * dist, s[1] + c * dist
        if self.zone is not None and self.zone.hits_segment(s[0], s[1], nx, ny):
            return None
        if self.terrain is not None and not self.terrain.translation_ok(s, nx, ny):
            return None
        return self._with_key((nx, ny, s[2], s[3], s[4] - dist, s[5], s[6] - dist, s[7],
                               s[8] - dist, s[9], s[10] - dist))

    def body_moves(self, s: tuple) -> list[tuple[int, tuple, float]]:
        out = []
        model = self.model
        delta = heading_error(s, self.goal, self.sense)
        if abs(delta) > MIN_MOVE:
            direction = 1.0 if delta > 0 else -1.0
            turn = direction * min(abs(delta), rotation_limit(model, s, direction))
            if abs(turn) > MIN_MOVE and (self.terrain is None or
                                         self.terrain.rotation_ok(s, turn)):
                c, sn = math.cos(turn), math.sin(turn)  # feet turn by -turn in body frame
                feet: list[float] = []
                for i in range(4):
                    px, py = s[3 + 2 * i], s[4 + 2 * i]
                    feet += (c * px + sn * py, -sn * px + c * py)
                out.append((1, self._with_key((s[0], s[1], s[2] + turn, *feet)), 1.0))
        gx, gy = self.goal[0] - s[0], self.goal[1] - s[1]
        along = -math.sin(s[2]) * gx + math.cos(s[2]) * gy  # goal on the body Y axis
        sign = float(self.sense) if self.sense else (1.0 if along >= 0 else -1.0)
        limit = translation_limit(model, s, sign)
        if limit >= model.b / 3 - EPS:
            child = self._translate(s, sign * model.b / 3)
            if child is not None:
                out.append((2, child, 1.0))
        reach = min(limit, max(0.0, sign * along))
        if reach > MIN_MOVE:
            child = self._translate(s, sign * reach)
            if child is not None:
                out.append((3, child, 1.0))
        if self.shifts:
            terrain = self.terrain
            for rule, dx, dy in shift_moves(model, s, _liftable(s, self._stable),
                                            self._shift_cache):
                if terrain is None or terrain.translation_ok(s, s[0] + dx, s[1] + dy):
                    out.append((rule, self._with_key(shifted(s, dx, dy)), 1.0))
        return out

    # -- leg moves --------------------------------------------------------------------------
    def _leg_moves(self, s: tuple, out: list) -> None:
        append = out.append
        for rule, leg, fx, fy, key in self.leg_targets(s):
            j = 3 + 2 * leg
            append((rule, (*s[:j], fx, fy, *s[j + 2:11], key), 1.0))

    def leg_targets(self, s: tuple) -> list[tuple[int, int, float, float, int]]:
        """The applicable leg rules of ``s`` as ``(rule, leg, fx, fy, child_key)`` (new
        body-frame foot, key of the child state), in rule order (4-7, 8-11, then 12-27 leg
        by leg); the child is ``s`` with foot ``leg`` at (fx, fy), built only when needed."""
        key = s[11]
        opts = self.leg_options(s)
        return [(rule, leg, fx, fy, key + dk) for part in self.parts for leg, opt in opts
                for rule, fx, fy, dk in opt[part]]

    def leg_options(self, s: tuple) -> list[tuple[int, tuple[tuple, ...]]]:
        """``(leg, moves)`` of the legs that may be lifted (stability), ``moves`` as in
        :meth:`_leg_options` less those into the exclusion zone."""
        lift = _liftable(s, self._stable)
        opts = self._leg_options
        out: list[tuple[int, tuple[tuple, ...]]] = [
            (leg, opts(leg, s[j], s[j + 1])) for leg, j in ((0, 3), (1, 5), (2, 7), (3, 9))
            if lift[leg]]
        zone = self.zone
        if zone is not None and out:  # drop the moves that put a foot into the zone
            c, sn = math.cos(s[2]), math.sin(s[2])
            x, y, inside = s[0], s[1], zone.contains
            out = [(leg, tuple(tuple(m for m in part
                                     if not inside(x + c * m[1] - sn * m[2],
                                                   y + sn * m[1] + c * m[2]))
                               for part in moves)) for leg, moves in out]
        terrain = self.terrain
        if terrain is not None and out and not terrain.feet_open(s[0], s[1]):
            out = _feet_on_terrain(terrain, s, out)
        return out

    def _leg_options(self, leg: int, px: float, py: float) -> tuple[tuple, tuple, tuple]:
        """The moves of one foot at body-frame (px, py), as ``(rule, fx, fy, key change)``:
        rule 4+leg, rule 8+leg, rules 12-27 of the leg (only those that move the foot).
        They depend on the foot alone, so they are memoised per foot position."""
        cache = self._options[leg]
        got = cache.get((px, py))
        if got is not None:
            return got
        q = self._q
        j = 3 + 2 * leg
        wx, wy = KEY_WEIGHT[j], KEY_WEIGHT[j + 1]
        own = round(px * q) * wx + round(py * q) * wy
        parts: list[tuple[tuple[int, float, float, int], ...]] = []
        for rule, fx, fy, kp in self._fixed_keyed[leg]:  # rules 4 + leg and 8 + leg
            if -1e-7 < fx - px < 1e-7 and -1e-7 < fy - py < 1e-7:
                parts.append(())
            else:
                parts.append(((rule, fx, fy, kp - own),))
        free = []
        if self.n_rules == 27:
            hx, hy = self._hips[leg]
            lmax, lmin = self.model.l_max, self.model.l_min
            rx, ry = px - hx, py - hy
            length = math.hypot(rx, ry)
            ux, uy = rx / length, ry / length
            (mx, my), (nx, ny) = self._unit_max[leg], self._unit_min[leg]
            for rule, fx, fy in ((12 + leg, hx + lmax * ux, hy + lmax * uy),
                                 (16 + leg, hx + lmin * ux, hy + lmin * uy),
                                 (20 + leg, hx + length * mx, hy + length * my),
                                 (24 + leg, hx + length * nx, hy + length * ny)):
                if not (-1e-7 < fx - px < 1e-7 and -1e-7 < fy - py < 1e-7):
                    free.append((rule, fx, fy, round(fx * q) * wx + round(fy * q) * wy - own))
        got = (parts[0], parts[1], tuple(free))
        if len(cache) >= OPTIONS_CACHE:
            cache.clear()
        cache[(px, py)] = got
        return got


def _feet_on_terrain(terrain: Any, s: tuple, options: list) -> list:
    """``options`` of :meth:`WalkProblem.leg_options` less the moves that put a foot where
    ``terrain.foot_ok`` refuses it (its grid lookup inlined: this is the hot path)."""
    c, sn = math.cos(s[2]), math.sin(s[2])
    x, y = s[0], s[1]
    x0, y0, inv, nx, ny = terrain.x0, terrain.y0, terrain.inv, terrain.nx, terrain.ny
    rows, thr = terrain._foot_rows, terrain.foot_thr
    out = []
    for leg, moves in options:
        parts = []
        for part in moves:
            keep = []
            for m in part:
                i = int((x + c * m[1] - sn * m[2] - x0) * inv + 0.5)
                j = int((y + sn * m[1] + c * m[2] - y0) * inv + 0.5)
                if 0 <= i < nx and 0 <= j < ny and rows[i][j] >= thr:
                    keep.append(m)
            parts.append(keep)
        out.append((leg, parts))
    return out


def _liftable(s: tuple, stable: float) -> list[bool]:
    """For each leg: is the body centre (origin) at least ``stable`` inside the triangle of
    the three other feet? (Signed edge distances: cross products of the foot vectors over
    the edge lengths; the triangle's orientation flips the sign.)"""
    ax, ay, bx, by, cx, cy, dx, dy = s[3:11]
    hyp = math.hypot
    # signed edge terms (cross products of the foot vectors) and edge lengths
    ab, bc, cd, da = ax * by - ay * bx, bx * cy - by * cx, cx * dy - cy * dx, dx * ay - dy * ax
    ac, bd = ax * cy - ay * cx, bx * dy - by * dx
    lab, lbc, lcd, lda = hyp(bx - ax, by - ay), hyp(cx - bx, cy - by), hyp(dx - cx, dy - cy), \
        hyp(ax - dx, ay - dy)
    lac, lbd = hyp(cx - ax, cy - ay), hyp(dx - bx, dy - by)
    return [_tri(bc, cd, -bd, lbc, lcd, lbd) >= stable,  # without 0: b, c, d
            _tri(cd, da, ac, lcd, lda, lac) >= stable,   # without 1: c, d, a
            _tri(da, ab, bd, lda, lab, lbd) >= stable,   # without 2: d, a, b
            _tri(ab, bc, -ac, lab, lbc, lac) >= stable]  # without 3: a, b, c


def _tri(e1: float, e2: float, e3: float, l1: float, l2: float, l3: float) -> float:
    """Margin of the origin in a triangle from its three edge cross terms and lengths."""
    orient = e1 + e2 + e3  # twice the signed area
    if orient == 0 or l1 == 0 or l2 == 0 or l3 == 0:
        return -math.inf
    d1, d2, d3 = e1 / l1, e2 / l2, e3 / l3
    if orient > 0:
        m = d1 if d1 < d2 else d2
        return m if m < d3 else d3
    m = d1 if d1 > d2 else d2
    return -(m if m > d3 else d3)
