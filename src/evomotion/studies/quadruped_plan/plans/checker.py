"""Independent re-verification of a ``plan.json`` (paper 003 model).

Written apart from ``rules``/``model``: feet are checked in leg polar coordinates, margins
through ``scipy.spatial.ConvexHull``, and body moves by sampling the path (``PATH_SAMPLES``
points) instead of the analytic limits the planner uses. The first violation raises
:class:`PlanViolationError` naming the state.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.spatial import ConvexHull

from evomotion.core.angles import wrap_angle as _wrap
from evomotion.studies.quadruped_plan.worlds.check import WorldGeometry

TOL = 1e-6  # [units] / [rad]
PATH_SAMPLES = 64
MAX_SLACK = 1e-3  # rules 1 and 3 must go as far as allowed: 1e-3 further must be infeasible
RULE_COUNT = {"A": 11, "B": 27}


class PlanViolationError(Exception):
    """A plan state or transition that breaks the model; ``str()`` is one line."""


class _Geometry:
    def __init__(self, m: dict[str, Any]) -> None:
        self.a, self.b = float(m["a"]), float(m["b"])
        self.lmin, self.lmax = float(m["l_min"]), float(m["l_max"])
        self.hw = float(m["sector_half_width"])
        self.min_margin = float(m.get("min_margin", 0.0))
        a2, b2 = self.a / 2, self.b / 2
        self.hips = np.array([[-a2, b2], [-a2, -b2], [a2, -b2], [a2, b2]])
        self.nominal = np.array([math.pi, math.pi, 0.0, 0.0])

    def body_feet(self, body: np.ndarray, feet: np.ndarray) -> np.ndarray:
        c, s = math.cos(body[2]), math.sin(body[2])
        d = feet - body[:2]
        return np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=1)

    def polar(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rel = p - self.hips
        length = np.hypot(rel[:, 0], rel[:, 1])
        off = np.angle(np.exp(1j * (np.arctan2(rel[:, 1], rel[:, 0]) - self.nominal)))
        return length, off

    def outside(self, p: np.ndarray, tol: float = TOL) -> int | None:
        """First leg whose body-frame foot is outside its sector, else None. (The
        "stops short" tests use ``tol = 0``: 1e-3 beyond a tangent exit, a foot is only
        ~1e-6 outside the circle.)"""
        length, off = self.polar(p)
        bad = (length < self.lmin - tol) | (length > self.lmax + tol) | (np.abs(off) >
                                                                         self.hw + tol)
        return int(np.argmax(bad)) if bad.any() else None

    def rear_offset(self, leg: int) -> float:
        """Angle offset of the sector edge pointing to body -Y (the paper's maximum angle)."""
        return self.hw if math.sin(self.nominal[leg] + self.hw) < 0 else -self.hw


def hull_margin(points: np.ndarray, centre: np.ndarray) -> float:
    """Signed distance of ``centre`` to the boundary of the hull of ``points`` (> 0 inside)."""
    try:
        hull = ConvexHull(points)
    except Exception:  # degenerate (collinear) support
        return -math.inf
    eq = hull.equations  # n . x + d <= 0 inside, |n| = 1
    return float(-np.max(eq[:, :2] @ centre + eq[:, 2]))


def check_plan(doc: dict[str, Any]) -> dict[str, float]:
    """Verify every state and transition; return a summary or raise PlanViolationError."""
    g = _Geometry(doc["model"])
    goal = np.array(doc["goal"], dtype=float)
    tol_goal = float(doc["goal_tolerance"])
    sense = int(doc.get("sense", -1))
    n_rules = RULE_COUNT.get(doc["rule_set"])
    if n_rules is None:
        raise PlanViolationError(f"unknown rule set {doc['rule_set']!r}")
    zone = doc.get("zone")
    states = doc["states"]
    bodies = [np.array(s["body"], dtype=float) for s in states]
    feet = [np.array(s["feet"], dtype=float) for s in states]
    legs = 0
    travel = 0.0
    wg = WorldGeometry(doc["world"], g.a, g.b) if doc.get("world") else None
    executed = bool(doc.get("executed"))
    moved_max = float(doc.get("disturbance_max", 0.0))
    for i, st in enumerate(states):
        event = st.get("event", "") if executed else ""
        where = f"state {i} (rule {st['rule']}{', ' + event if event else ''})"
        p = g.body_feet(bodies[i], feet[i])
        leg = g.outside(p)
        if leg is not None:
            raise PlanViolationError(f"{where}: foot {leg} is outside its workspace")
        if zone is not None:
            zc = np.array([zone["x"], zone["y"]])
            if np.linalg.norm(bodies[i][:2] - zc) < zone["radius"] - TOL or np.any(
                    np.linalg.norm(feet[i] - zc, axis=1) < zone["radius"] - TOL):
                raise PlanViolationError(f"{where}: body or foot inside the exclusion zone")
        if wg is not None:
            wg.check_feet(feet[i], i, where, PlanViolationError)
            wg.check_body(bodies[i][None], i, where, PlanViolationError)
        rule = st["rule"]
        target = np.array(st.get("target", doc["goal"]), dtype=float)
        if i == 0:
            if rule != 0:
                raise PlanViolationError(f"{where}: the start state must have rule 0")
            margin = hull_margin(feet[0], bodies[0][:2])
        elif rule == 0 and event:
            _check_disturbance(bodies[i - 1], feet[i - 1], bodies[i], feet[i], moved_max,
                               event, where)
            margin = hull_margin(feet[i], bodies[i][:2])
        elif 28 <= rule <= 32 and executed or 28 <= rule <= 31 and doc.get("shifts"):
            _check_extra_move(g, bodies[i - 1], feet[i - 1], bodies[i], feet[i], rule, sense,
                              where)
            if wg is not None:
                wg.check_body(wg.poses(bodies[i - 1], bodies[i]), i, where, PlanViolationError)
            travel += float(np.linalg.norm(bodies[i][:2] - bodies[i - 1][:2]))
            margin = hull_margin(feet[i], bodies[i][:2])
        elif not 1 <= rule <= n_rules:
            raise PlanViolationError(f"{where}: no such rule in set {doc['rule_set']}")
        elif rule <= 3:
            _check_body_move(g, bodies[i - 1], feet[i - 1], bodies[i], feet[i], rule, target,
                             sense, zone, where)
            if wg is not None:
                wg.check_body(wg.poses(bodies[i - 1], bodies[i]), i, where, PlanViolationError)
            travel += float(np.linalg.norm(bodies[i][:2] - bodies[i - 1][:2]))
            margin = hull_margin(feet[i], bodies[i][:2])
        else:
            leg = (rule - 4) % 4
            _check_leg_move(g, bodies[i - 1], feet[i - 1], bodies[i], feet[i], rule, leg, where)
            legs += 1
            margin = hull_margin(np.delete(feet[i - 1], leg, axis=0), bodies[i][:2])
            if margin < g.min_margin - 1e-9:
                raise PlanViolationError(f"{where}: leg {leg} lifted with margin {margin:.4g} < "
                                    f"{g.min_margin:g}")
        if margin < -1e-9:
            raise PlanViolationError(f"{where}: statically unstable (margin {margin:.4g})")
        if abs(margin - float(st["margin"])) > TOL:
            raise PlanViolationError(f"{where}: margin {st['margin']:.6g} recorded, "
                                f"{margin:.6g} recomputed")
    dist = float(np.linalg.norm(bodies[-1][:2] - goal))
    if dist > tol_goal + TOL:
        raise PlanViolationError(f"state {len(states) - 1}: ends {dist:.3f} from the goal "
                            f"(tolerance {tol_goal:g})")
    return {"states": len(states), "leg_moves": legs, "travel": travel,
            "leg_moves_per_unit": legs / travel if travel > 0 else math.inf}


def _check_disturbance(b0: np.ndarray, f0: np.ndarray, b1: np.ndarray, f1: np.ndarray,
                       moved_max: float, event: str, where: str) -> None:
    """A landing error or a slip: the body stays, one foot moves by at most ``moved_max``."""
    if event != "landing" and not event.startswith("slip"):
        raise PlanViolationError(f"{where}: unknown event {event!r}")
    if np.max(np.abs(b1 - b0)) > TOL:
        raise PlanViolationError(f"{where}: the body moved during a {event}")
    moved = np.linalg.norm(f1 - f0, axis=1)
    if np.count_nonzero(moved > TOL) > 1:
        raise PlanViolationError(f"{where}: more than one foot moved in a {event}")
    if moved.max() > moved_max + TOL:
        raise PlanViolationError(f"{where}: a foot moved {moved.max():.3f} in a {event} "
                                 f"(at most {moved_max:g})")


SHIFT_MAX = 0.3  # [units] the longest body shift (rules 28-31)


def _check_extra_move(g: _Geometry, b0: np.ndarray, f0: np.ndarray, b1: np.ndarray,
                      f1: np.ndarray, rule: int, sense: int, where: str) -> None:
    """A body shift freeing leg rule - 28 (28-31) or a step back (32): feet fixed, no
    rotation, every foot in its sector along the straight path."""
    if np.max(np.abs(f1 - f0)) > TOL:
        raise PlanViolationError(f"{where}: a foot moved during a body move")
    if abs(_wrap(b1[2] - b0[2])) > TOL:
        raise PlanViolationError(f"{where}: rule {rule} rotated the body")
    d = b1[:2] - b0[:2]
    if rule == 32:
        axis = np.array([-math.sin(b0[2]), math.cos(b0[2])])
        along = float(d @ axis)
        if np.linalg.norm(d - along * axis) > TOL or along * (-1 if sense < 0 else 1) > TOL \
                or abs(along) > g.b / 3 + TOL:
            raise PlanViolationError(f"{where}: a step back must go at most b/3 against the "
                                     "walking sense along the body Y axis")
    else:
        leg = rule - 28
        if np.linalg.norm(d) > SHIFT_MAX + TOL:
            raise PlanViolationError(f"{where}: a shift of {np.linalg.norm(d):.3f} "
                                     f"(at most {SHIFT_MAX:g})")
        if hull_margin(np.delete(f1, leg, axis=0), b1[:2]) < g.min_margin - 1e-9:
            raise PlanViolationError(f"{where}: rule {rule} does not free leg {leg}")
    for t in np.linspace(0.0, 1.0, PATH_SAMPLES):
        out = g.outside(g.body_feet(b0 + t * (b1 - b0), f0))
        if out is not None:
            raise PlanViolationError(f"{where}: foot {out} leaves its workspace during the move")


def _check_body_move(g: _Geometry, b0: np.ndarray, f0: np.ndarray, b1: np.ndarray,
                     f1: np.ndarray, rule: int, goal: np.ndarray, sense: int,
                     zone: dict | None, where: str) -> None:
    if np.max(np.abs(f1 - f0)) > TOL:
        raise PlanViolationError(f"{where}: a foot moved during a body move")
    ts = np.linspace(0.0, 1.0, PATH_SAMPLES)
    if rule == 1:
        if np.linalg.norm(b1[:2] - b0[:2]) > TOL:
            raise PlanViolationError(f"{where}: a rotation moved the body centre")
        turn = _wrap(b1[2] - b0[2])
        heading = b0[2] + (-math.pi / 2 if sense < 0 else math.pi / 2)
        bearing = math.atan2(goal[1] - b0[1], goal[0] - b0[0])
        before = _wrap(bearing - heading)
        if sense == 0 and abs(before) > math.pi / 2:
            before = _wrap(before - math.pi)
        if abs(turn) < TOL or turn * before < 0 or abs(turn) > abs(before) + TOL:
            raise PlanViolationError(f"{where}: the rotation does not reduce the heading error")
        path = [np.array([b0[0], b0[1], b0[2] + t * turn]) for t in ts]
        if abs(turn) < abs(before) - MAX_SLACK and g.outside(g.body_feet(
                np.array([b0[0], b0[1], b0[2] + turn + np.sign(turn) * MAX_SLACK]), f0),
                0.0) is None:
            raise PlanViolationError(f"{where}: rule 1 stops short of the workspace limit")
    else:
        d = b1[:2] - b0[:2]
        axis = np.array([-math.sin(b0[2]), math.cos(b0[2])])
        along = float(d @ axis)
        if abs(_wrap(b1[2] - b0[2])) > TOL or np.linalg.norm(d - along * axis) > TOL:
            raise PlanViolationError(f"{where}: a translation not along the body Y axis")
        if sense != 0 and along * sense < 0:
            raise PlanViolationError(f"{where}: a translation against the walking sense")
        if rule == 2 and abs(abs(along) - g.b / 3) > TOL:
            raise PlanViolationError(f"{where}: rule 2 must translate by b/3, not {abs(along):.4f}")
        if rule == 3 and abs(along) > abs(float((goal - b0[:2]) @ axis)) + TOL:
            raise PlanViolationError(f"{where}: rule 3 overshoots the goal along the axis")
        path = [np.array([b0[0] + t * d[0], b0[1] + t * d[1], b0[2]]) for t in ts]
        further = np.array([*(b1[:2] + np.sign(along) * MAX_SLACK * axis), b0[2]])
        if rule == 3 and abs(along) < abs(float((goal - b0[:2]) @ axis)) - MAX_SLACK and \
                g.outside(g.body_feet(further, f0), 0.0) is None:
            raise PlanViolationError(f"{where}: rule 3 stops short of the workspace limit")
    for b in path:
        leg = g.outside(g.body_feet(b, f0))
        if leg is not None:
            raise PlanViolationError(f"{where}: foot {leg} leaves its workspace during the move")
        if zone is not None and math.hypot(b[0] - zone["x"], b[1] - zone["y"]) < \
                zone["radius"] - TOL:
            raise PlanViolationError(f"{where}: the body passes through the exclusion zone")


def _check_leg_move(g: _Geometry, b0: np.ndarray, f0: np.ndarray, b1: np.ndarray,
                    f1: np.ndarray, rule: int, leg: int, where: str) -> None:
    if np.max(np.abs(b1 - b0)) > TOL:
        raise PlanViolationError(f"{where}: the body moved during a leg move")
    others = [k for k in range(4) if k != leg]
    if np.max(np.abs(f1[others] - f0[others])) > TOL:
        raise PlanViolationError(f"{where}: a foot other than leg {leg} moved")
    l0, o0 = g.polar(g.body_feet(b0, f0))
    l1, o1 = g.polar(g.body_feet(b1, f1))
    rear = g.rear_offset(leg)
    group = (rule - 4) // 4  # 0: max/max, 1: mid/nominal, 2: max L, 3: min L, 4: max, 5: min
    want_len = [g.lmax, 0.5 * (g.lmin + g.lmax), g.lmax, g.lmin, l0[leg], l0[leg]][group]
    want_off = [rear, 0.0, o0[leg], o0[leg], rear, -rear][group]
    if abs(l1[leg] - want_len) > TOL or abs(_wrap(o1[leg] - want_off)) > TOL:
        raise PlanViolationError(f"{where}: leg {leg} is not where rule {rule} puts it")
    if np.max(np.abs(f1[leg] - f0[leg])) < TOL:
        raise PlanViolationError(f"{where}: rule {rule} does not move leg {leg}")
