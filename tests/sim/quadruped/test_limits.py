"""The simulated quadruped refuses what it cannot be, and a plan's execution time is known
from its numbers before anything of that length is allocated."""

from __future__ import annotations

import math

import numpy as np
import pytest

from evomotion.sim.quadruped import QuadrupedSpec, simulate_plan
from evomotion.sim.quadruped.execute import (
    FINAL_SECONDS,
    LEG_SECONDS,
    METRES_PER_SECOND,
    RADIANS_PER_SECOND,
    SETTLE_SECONDS,
)
from evomotion.sim.quadruped.trajectory import build_timeline, plan_seconds


@pytest.mark.parametrize(("field", "value", "words"), [
    ("a", math.nan, "a: expected a finite number"),
    ("kp", math.inf, "kp: expected a finite number"),
    ("a", 1e5, "larger than 5 m"),
    ("b", 60.0, "larger than 5 m"),
    ("l_max", 40.0, "legs cannot reach"),
])
def test_a_spec_out_of_its_physical_range_is_refused(field, value, words):
    with pytest.raises(ValueError, match=words):
        QuadrupedSpec(**{field: value})


def _states(spec: QuadrupedSpec, far: float = 0.0) -> list[dict]:
    h = spec.hips_m()[:, :2] / spec.unit_m
    feet = (h + [[-1.5, 0], [-1.5, 0], [1.5, 0], [1.5, 0]])
    moved = feet.copy()
    moved[0, 1] += 0.4
    turned = moved + [0.0, -0.5 - far]
    return [{"body": [0.0, 0.0, 0.0], "feet": feet.tolist(), "rule": 0},
            {"body": [0.0, 0.0, 0.0], "feet": moved.tolist(), "rule": 4},
            {"body": [0.0, -0.5 - far, 0.2], "feet": turned.tolist(), "rule": 3}]


def test_plan_seconds_is_the_timeline_length():
    spec = QuadrupedSpec()
    states = _states(spec)
    kw = dict(leg_seconds=LEG_SECONDS, metres_per_second=METRES_PER_SECOND,
              radians_per_second=RADIANS_PER_SECOND, settle_seconds=SETTLE_SECONDS,
              final_seconds=FINAL_SECONDS)
    tl = build_timeline(spec, states, lift_m=0.012, **kw)
    assert plan_seconds(spec, states, **kw) == pytest.approx(len(tl.q) * spec.timestep)
    bad = [dict(s) for s in states]
    bad[1] = dict(bad[1], body=[math.nan, 0.0, 0.0])
    assert plan_seconds(spec, bad, **kw) == math.inf


def test_an_execution_too_long_is_refused_before_it_is_built():
    spec = QuadrupedSpec()
    with pytest.raises(ValueError, match="would last 2e\\+05 simulated seconds"):
        simulate_plan(_states(spec, far=1e5), spec)  # 10 km at 5 cm/s
    res, _ = simulate_plan(_states(spec), spec, settle_seconds=0.1, final_seconds=0.1)
    assert res.steps > 0 and np.isfinite(res.min_body_height_m)
