"""Evaluation functions (1)-(3) of seed 003 and an admissible A* heuristic.

Terms (seed section 4): ``vzd(i)`` the distance of the body centre from the goal,
``dev(i)`` the deviation of the body Y axis from the goal direction [rad], ``step(i)`` = 1
when state ``i`` came from its parent ``j`` by a leg rule, else 0.

(1)  f(i) = k1 vzd(i) + k2 dev(i)                                       k1 = 1, k2 = 5
(2)  f(i) = k1 (vzd(i) - vzd(j)) + k2 (dev(i) - dev(j)) + f(j)           k1 = 1, k2 = 5
(3)  f(i) = k1 (vzd(i) - vzd(j)) + k2 (dev(i) - dev(j)) + k3 step + f(j)
            set A: k1 = 1, k2 = 5, k3 = 0.4;   set B: k1 = 1, k2 = 50, k3 = 0.2
with f(s0) = k1 vzd(s0) + k2 dev(s0). (2) telescopes to (1) plus a constant along any
path; (3) telescopes to (1) + k3 * (leg moves on the path), i.e. g + h with g = k3 * legs.

The A* heuristic bounds the remaining plan length (transitions, every rule costs 1):
with d = max(0, vzd - goal_tolerance), at least ceil(d / T) translations, T = 2 l_max
sin(half width) the longest straight chord of a sector along the body Y axis; and each of
the four feet must be moved at least ceil(d / D) - 1 times, D = 2 r_max, where r_max is the
farthest a foot can be from the body centre: while a foot stays planted at F the centre
stays within r_max of F, so it moves at most D. Rotations move the centre not at all.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from evomotion.studies.quadruped_plan.model import QuadrupedModel
from evomotion.studies.quadruped_plan.rules import heading_error

# seed's constants (k1, k2, k3) per function and rule set
SEED_CONSTANTS: dict[tuple[int, str], tuple[float, float, float]] = {
    (1, "A"): (1.0, 5.0, 0.0), (1, "B"): (1.0, 5.0, 0.0),
    (2, "A"): (1.0, 5.0, 0.0), (2, "B"): (1.0, 5.0, 0.0),
    (3, "A"): (1.0, 5.0, 0.4), (3, "B"): (1.0, 50.0, 0.2),
}


def vzd(state: tuple[float, ...], goal: tuple[float, float]) -> float:
    return math.hypot(goal[0] - state[0], goal[1] - state[1])


def dev(state: tuple[float, ...], goal: tuple[float, float], sense: int = -1) -> float:
    return abs(heading_error(state, goal, sense))


def seed_evaluation(function: int, k: tuple[float, float, float], goal: tuple[float, float],
                    sense: int = -1) -> Callable[..., float]:
    """The evaluation ``evaluate(pf, pg, ps, child, rule, cost)`` of seed function 1, 2 or 3."""
    k1, k2, k3 = k
    if function != 3:
        k3 = 0.0  # only function (3) counts leg moves
    if function not in (1, 2, 3):
        raise ValueError(f"unknown evaluation function {function}; available: 1, 2, 3")
    gx, gy = goal
    hypot, he = math.hypot, heading_error

    def direct(s: tuple[float, ...]) -> float:
        return k1 * hypot(gx - s[0], gy - s[1]) + k2 * abs(he(s, goal, sense))

    if function == 1:  # a leg move leaves vzd and dev (hence f) unchanged
        return lambda pf, pg, ps, child, rule, cost: pf if rule and rule >= 4 else direct(child)

    def cumulative(pf: Any, pg: Any, ps: Any, child: tuple[float, ...], rule: Any,
                   cost: float) -> float:
        if pf is None:
            return direct(child)
        if rule >= 4:  # a leg move leaves vzd and dev unchanged
            return pf + k3
        return pf + direct(child) - direct(ps)

    return cumulative


def _polar_span(model: QuadrupedModel, leg: int, samples: int = 4000) -> float:
    """Upper bound [rad] of the spread of polar angles (about the body centre) over the
    sector of ``leg``: densely sampled boundary plus a 1e-3 rad safety margin."""
    hw, nom = model.sector_half_width, model.nominal_angle(leg)
    pts = []
    for k in range(samples + 1):
        u = k / samples
        beta = nom - hw + 2 * hw * u
        pts += [model.foot_at(leg, model.l_max, beta), model.foot_at(leg, model.l_min, beta)]
        length = model.l_min + (model.l_max - model.l_min) * u
        pts += [model.foot_at(leg, length, nom - hw), model.foot_at(leg, length, nom + hw)]
    ref = math.atan2(*reversed(model.foot_at(leg, model.l_max, nom)))
    offs = [(math.atan2(py, px) - ref + math.pi) % (2 * math.pi) - math.pi for px, py in pts]
    return max(offs) - min(offs) + 1e-3


def heuristic_constants(model: QuadrupedModel) -> tuple[float, float, float]:
    """(T, D, G): the longest single translation; the longest centre travel per foot stance;
    the most one rotation can add to the summed foot room (module docstring)."""
    hw = model.sector_half_width
    chord = 2 * model.l_max * math.sin(hw)
    r_max = 0.0
    for leg, (hx, hy) in enumerate(model.hips):
        lo, hi = model.nominal_angle(leg) - hw, model.nominal_angle(leg) + hw
        toward = math.atan2(hy, hx)
        candidates = [lo, hi]
        for shift in (-2 * math.pi, 0.0, 2 * math.pi):
            if lo <= toward + shift <= hi:
                candidates.append(toward + shift)
        for beta in candidates:
            fx, fy = model.foot_at(leg, model.l_max, beta)
            r_max = max(r_max, math.hypot(fx, fy))
    rho = min(min(_polar_span(model, leg) for leg in range(4)), math.pi)
    sum_x = 2 * (model.l_max - model.l_min * math.cos(hw))
    sum_y = 2 * chord
    gain = math.sin(rho) * sum_x + (1 - math.cos(rho)) * sum_y
    return chord, 2 * r_max, gain


def foot_room(model: QuadrupedModel, state: tuple[float, ...], sense: int) -> float:
    """Summed room of the four feet along the walking direction: sum of (T/2 -+ y_rel)."""
    half = model.l_max * math.sin(model.sector_half_width)
    hips = model.hips
    return sum(half + sense * (state[4 + 2 * i] - hips[i][1]) for i in range(4))


def plan_length_heuristic(model: QuadrupedModel, goal: tuple[float, float],
                          goal_tolerance: float, sense: int = -1
                          ) -> Callable[[tuple[float, ...]], float]:
    """Admissible lower bound on the transitions still needed (see the module docstring)."""
    chord, stance, gain = heuristic_constants(model)
    per_move = max(chord, gain)
    gx, gy = goal
    # foot_room(s) = room0 + sense * (sum of the feet's body y)
    room0 = 4 * model.l_max * math.sin(model.sector_half_width) - sense * sum(
        hy for _, hy in model.hips)
    ceil, hypot = math.ceil, math.hypot

    def h(s: tuple[float, ...]) -> float:
        d = hypot(gx - s[0], gy - s[1]) - goal_tolerance
        if d <= 0:
            return 0.0
        trans = ceil(d / chord - 1e-9)
        if sense == 0:
            return trans + 4 * max(0, ceil(d / stance - 1e-9) - 1)
        room = room0 + sense * (s[4] + s[6] + s[8] + s[10])
        need = (4 * d - room) / per_move
        return trans + max(0, ceil(need - 1e-9))

    return h
