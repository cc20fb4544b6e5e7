"""Physics steps per control period: a closed loop reads its sensors and sets its targets
every ``period_s``, which must be a whole number of its model's physics steps (the policy
then sees the same instants in training, in the exports and on the robot)."""

from __future__ import annotations

import math

#: how far ``period_s / timestep_s`` may lie from a whole number (float rounding)
TOLERANCE = 1e-6


def whole_steps(period_s: float, timestep_s: float, max_steps: int | None = None
                ) -> int | None:
    """``period_s / timestep_s`` rounded, where it is a whole number of at least 1 (and at most
    ``max_steps``), else None: the caller says in one line what was expected of which key."""
    k = float(period_s) / float(timestep_s)
    if not math.isfinite(k) or abs(k - round(k)) > TOLERANCE:
        return None
    n = round(k)
    return n if n >= 1 and (max_steps is None or n <= max_steps) else None
