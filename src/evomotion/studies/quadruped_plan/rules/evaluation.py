"""Evaluation functions (1)-(3) of paper 003 (the A* heuristic is in ``heuristic``).

Terms (the paper's section 4): ``vzd(i)`` the distance of the body centre from the goal,
``dev(i)`` the deviation of the body Y axis from the goal direction [rad], ``step(i)`` = 1
when state ``i`` came from its parent ``j`` by a leg rule, else 0.

(1)  f(i) = k1 vzd(i) + k2 dev(i)                                       k1 = 1, k2 = 5
(2)  f(i) = k1 (vzd(i) - vzd(j)) + k2 (dev(i) - dev(j)) + f(j)           k1 = 1, k2 = 5
(3)  f(i) = k1 (vzd(i) - vzd(j)) + k2 (dev(i) - dev(j)) + k3 step + f(j)
            set A: k1 = 1, k2 = 5, k3 = 0.4;   set B: k1 = 1, k2 = 50, k3 = 0.2
with f(s0) = k1 vzd(s0) + k2 dev(s0). (2) telescopes to (1) plus a constant along any
path; (3) telescopes to (1) + k3 * (leg moves on the path), i.e. g + h with g = k3 * legs.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from evomotion.studies.quadruped_plan.rules.rules import heading_error

# paper's constants (k1, k2, k3) per function and rule set
PAPER_CONSTANTS: dict[tuple[int, str], tuple[float, float, float]] = {
    (1, "A"): (1.0, 5.0, 0.0), (1, "B"): (1.0, 5.0, 0.0),
    (2, "A"): (1.0, 5.0, 0.0), (2, "B"): (1.0, 5.0, 0.0),
    (3, "A"): (1.0, 5.0, 0.4), (3, "B"): (1.0, 50.0, 0.2),
}


def vzd(state: tuple[float, ...], goal: tuple[float, float]) -> float:
    return math.hypot(goal[0] - state[0], goal[1] - state[1])


def dev(state: tuple[float, ...], goal: tuple[float, float], sense: int = -1) -> float:
    return abs(heading_error(state, goal, sense))


def paper_evaluation(function: int, k: tuple[float, float, float], goal: tuple[float, float],
                     sense: int = -1) -> Callable[..., float]:
    """The evaluation ``evaluate(pf, pg, ps, child, rule, cost)`` of the paper's function 1, 2
    or 3."""
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
        def absolute(pf: Any, pg: Any, ps: Any, child: tuple[float, ...], rule: Any,
                     cost: float) -> float:
            return pf if rule and rule >= 4 and rule <= 27 else direct(child)

        absolute.leg_delta = 0.0  # type: ignore[attr-defined]  # see walk_search
        return absolute

    def cumulative(pf: Any, pg: Any, ps: Any, child: tuple[float, ...], rule: Any,
                   cost: float) -> float:
        if pf is None:
            return direct(child)
        if rule >= 4:
            if rule <= 27:  # a leg move leaves vzd and dev unchanged
                return pf + k3
            # a body shift (rules 28-31, beyond the paper) costs a step like a leg move
            return pf + direct(child) - direct(ps) + k3
        return pf + direct(child) - direct(ps)

    cumulative.leg_delta = k3  # type: ignore[attr-defined]  # f(child) - f(parent), leg rules
    return cumulative
