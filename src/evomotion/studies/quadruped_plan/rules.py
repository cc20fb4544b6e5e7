"""Production rules of seed 003 (section 4) and the walking-plan search problem.

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
Rules 1-3 are body moves, rules >= 4 leg moves (the seed's ``step`` = 1).
"""

from __future__ import annotations

import math
from collections.abc import Hashable
from dataclasses import dataclass

from evomotion.studies.quadruped_plan.model import (
    EPS,
    STABILITY_TOL,
    QuadrupedModel,
    rotation_limit,
    translation_limit,
)

RULE_SETS = {"A": 11, "B": 27}
MIN_MOVE = 1e-4  # a body move shorter than this [units or rad] is not applicable
POS_GRID = 0.01  # duplicate-detection grid for positions [units]
ANGLE_GRID = 0.001  # duplicate-detection grid for the body angle [rad]


def is_leg_rule(rule: int) -> bool:
    return rule >= 4


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
    """The state space of seed 003 as a :class:`evomotion.core.search.SearchProblem`.

    States are tuples ``(x, y, phi, p0x, p0y, ..., p3x, p3y)`` (see ``model``); every rule
    costs 1 (the plan length in transitions is the A* cost).
    """

    def __init__(self, model: QuadrupedModel, start: tuple[float, ...],
                 goal: tuple[float, float], rule_set: str = "A", goal_tolerance: float = 0.25,
                 sense: int = -1, zone: ExclusionZone | None = None) -> None:
        if rule_set not in RULE_SETS:
            raise ValueError(f"unknown rule set {rule_set!r}; available: A, B")
        self.model, self.goal, self.rule_set = model, goal, rule_set
        self.n_rules = RULE_SETS[rule_set]
        if sense not in (-1, 0, 1):
            raise ValueError(f"walking sense must be -1, 0 or +1, got {sense}")
        self.goal_tolerance, self.sense, self.zone = goal_tolerance, sense, zone
        self._start = self._with_key(tuple(float(v) for v in start))
        mid = 0.5 * (model.l_min + model.l_max)
        self._hips = model.hips
        self._unit_max = [(math.cos(model.max_angle(i)), math.sin(model.max_angle(i)))
                          for i in range(4)]
        self._unit_min = [(math.cos(model.min_angle(i)), math.sin(model.min_angle(i)))
                          for i in range(4)]
        self._fixed = []  # (rule, leg, fx, fy) of rules 4-11, body-frame feet
        for rule0, length, angle in ((4, model.l_max, model.max_angle),
                                     (8, mid, model.nominal_angle)):
            for leg in range(4):
                self._fixed.append((rule0 + leg, leg, *model.foot_at(leg, length, angle(leg))))
        self._stable = model.min_margin - STABILITY_TOL
        q = 1.0 / POS_GRID
        self._fixed_q = [(r, leg, fx, fy, round(fx * q), round(fy * q))
                         for r, leg, fx, fy in self._fixed]

    @staticmethod
    def _with_key(v: tuple[float, ...]) -> tuple:
        """The state tuple: the 11 floats followed by the duplicate key (see :meth:`key`)."""
        q = 1.0 / POS_GRID
        return (*v[:11], (round(v[0] * q), round(v[1] * q),
                          round((v[2] % (2 * math.pi)) / ANGLE_GRID),
                          round(v[3] * q), round(v[4] * q), round(v[5] * q), round(v[6] * q),
                          round(v[7] * q), round(v[8] * q), round(v[9] * q), round(v[10] * q)))

    def start(self) -> tuple:
        return self._start

    def is_goal(self, s: tuple) -> bool:
        return math.hypot(self.goal[0] - s[0], self.goal[1] - s[1]) <= self.goal_tolerance

    def key(self, s: tuple) -> Hashable:
        """Duplicates: body x, y and feet (body frame) on a POS_GRID grid, phi (mod 2 pi) on an
        ANGLE_GRID grid."""
        return s[11]

    def successors(self, s: tuple) -> list[tuple[int, tuple, float]]:
        out = self._body_moves(s)
        self._leg_moves(s, out)
        return out

    # -- body moves -------------------------------------------------------------------------
    def _translate(self, s: tuple, dist: float) -> tuple | None:
        c, sn = math.cos(s[2]), math.sin(s[2])
        nx, ny = s[0] - sn * dist, s[1] + c * dist
        if self.zone is not None and self.zone.hits_segment(s[0], s[1], nx, ny):
            return None
        return self._with_key((nx, ny, s[2], s[3], s[4] - dist, s[5], s[6] - dist, s[7],
                               s[8] - dist, s[9], s[10] - dist))

    def _body_moves(self, s: tuple) -> list[tuple[int, tuple, float]]:
        out = []
        model = self.model
        delta = heading_error(s, self.goal, self.sense)
        if abs(delta) > MIN_MOVE:
            direction = 1.0 if delta > 0 else -1.0
            turn = direction * min(abs(delta), rotation_limit(model, s, direction))
            if abs(turn) > MIN_MOVE:
                c, sn = math.cos(turn), math.sin(turn)  # feet turn by -turn in body frame
                feet = []
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
        return out

    # -- leg moves --------------------------------------------------------------------------
    def _leg_moves(self, s: tuple, out: list) -> None:
        lift = _liftable(s, self._stable)
        if not (lift[0] or lift[1] or lift[2] or lift[3]):
            return
        q = 1.0 / POS_GRID
        targets = [t for t in self._fixed_q if lift[t[1]]]
        if self.n_rules == 27:
            lmax, lmin = self.model.l_max, self.model.l_min
            for leg in range(4):
                if not lift[leg]:
                    continue
                hx, hy = self._hips[leg]
                rx, ry = s[3 + 2 * leg] - hx, s[4 + 2 * leg] - hy
                length = math.hypot(rx, ry)
                ux, uy = rx / length, ry / length
                (mx, my), (nx, ny) = self._unit_max[leg], self._unit_min[leg]
                for rule, fx, fy in ((12 + leg, hx + lmax * ux, hy + lmax * uy),
                                     (16 + leg, hx + lmin * ux, hy + lmin * uy),
                                     (20 + leg, hx + length * mx, hy + length * my),
                                     (24 + leg, hx + length * nx, hy + length * ny)):
                    targets.append((rule, leg, fx, fy, round(fx * q), round(fy * q)))
        zone = self.zone
        if zone is not None:
            c, sn = math.cos(s[2]), math.sin(s[2])
        key = s[11]
        append = out.append
        for rule, leg, fx, fy, qx, qy in targets:
            j = 3 + 2 * leg
            dx, dy = fx - s[j], fy - s[j + 1]
            if -1e-7 < dx < 1e-7 and -1e-7 < dy < 1e-7:
                continue  # the rule would not move the leg
            if zone is not None and zone.contains(s[0] + c * fx - sn * fy,
                                                  s[1] + sn * fx + c * fy):
                continue
            append((rule, (*s[:j], fx, fy, *s[j + 2:11],
                           (*key[:j], qx, qy, *key[j + 2:])), 1.0))


def _liftable(s: tuple, stable: float) -> list[bool]:
    """For each leg: is the body centre (origin) at least ``stable`` inside the triangle of
    the three other feet?"""
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
    return min(d1, d2, d3) if orient > 0 else -max(d1, d2, d3)
