"""The walker's recovery move (beyond the paper): step back.

The paper's rules never walk backwards, so a robot that meets an obstacle too close to turn
(one that came into view late, or a goal that moved behind it) or whose feet have all run
to the front of their sectors can be left with no applicable rule. When a replan finds no
applicable transition, the walker takes **rule 32, step back**: the body translates against
the walking sense by up to ``b/3``, as far as the workspaces and obstacles allow (feet
fixed, so stability is unchanged), and plans again. The checker verifies it like rules 1-3.
"""

from __future__ import annotations

import math

from evomotion.studies.quadruped_plan.rules.model import translation_limit
from evomotion.studies.quadruped_plan.rules.rules import WalkProblem

STEP_BACK = 32
MIN_STEP = 1e-3  # [units]


def step_back(problem: WalkProblem, s: tuple) -> tuple | None:
    """The state after stepping back from ``s``, or None when the body cannot."""
    model, terrain = problem.model, problem.terrain
    back = 1.0 if problem.sense < 0 else -1.0  # body +Y when walking towards body -Y
    t = min(model.b / 3, translation_limit(model, s, back))
    if t < MIN_STEP:
        return None
    c, sn = math.cos(s[2]), math.sin(s[2])
    nx, ny = s[0] - sn * back * t, s[1] + c * back * t
    if terrain is not None and not terrain.translation_ok(s, nx, ny):
        return None
    d = back * t
    return problem.make_state((nx, ny, s[2], s[3], s[4] - d, s[5], s[6] - d, s[7], s[8] - d,
                               s[9], s[10] - d))
