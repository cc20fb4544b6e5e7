"""The quadruped's body geometry is defined once (``sim/quadruped/geometry.py``): the rules
model, the ``[problem]`` defaults, the MuJoCo spec and the numbers the compiled successors
get all carry the same values."""

from __future__ import annotations

import math

import numpy as np

from evomotion.sim.quadruped import geometry as g
from evomotion.sim.quadruped.model import QuadrupedSpec
from evomotion.studies.quadruped_plan.plans.planner import QuadrupedPlanConfig
from evomotion.studies.quadruped_plan.rules.model import QuadrupedModel
from evomotion.studies.quadruped_plan.rules.rules import WalkProblem


def test_defaults_come_from_the_robot_geometry() -> None:
    want = (g.BODY_A, g.BODY_B, g.L_MIN, g.L_MAX, g.SECTOR_HALF_WIDTH)
    m, s, c = QuadrupedModel(), QuadrupedSpec(), QuadrupedPlanConfig()
    for obj in (m, s, c):
        assert (obj.a, obj.b, obj.l_min, obj.l_max, obj.sector_half_width) == want
    assert want == (2.5, 3.0, 1.0, 2.0, math.pi / 4)  # paper 003, Tab. 1


def test_hips_and_sectors_agree() -> None:
    m, s = QuadrupedModel(a=2.0, b=3.5), QuadrupedSpec(a=2.0, b=3.5)
    assert m.hips == g.hip_positions(2.0, 3.5) == ((-1.0, 1.75), (-1.0, -1.75), (1.0, -1.75),
                                                   (1.0, 1.75))
    assert np.array_equal(s.hips_m()[:, :2], np.array(m.hips) * s.unit_m)
    assert tuple(m.nominal_angle(i) for i in range(4)) == g.NOMINAL_ANGLES
    assert m.sides == g.LEG_SIDES


def _numbers(x: object) -> list[float]:
    if isinstance(x, float | int):
        return [float(x)]
    if isinstance(x, list | tuple):
        return [v for item in x for v in _numbers(item)]
    return []


def test_compiled_successors_get_the_model_numbers() -> None:
    """``_walkcore.c`` holds no geometry of its own: its constructor gets the model's hips
    and reach (checked here), and tests/studies/quadruped_plan/rules/test_walkcore.py checks its
    successors equal to the Python ones."""
    m = QuadrupedModel(a=2.0, b=3.5, l_min=0.75, l_max=2.25)
    numbers = _numbers(WalkProblem(m, m.nominal_state(0.0, 0.0, 0.0), (5.0, 5.0),
                                   "B")._core_args())
    assert numbers[:12] == [v for (hx, hy), side in zip(m.hips, m.sides, strict=True)
                            for v in (hx, hy, side)]
    assert {m.l_max, m.l_min, m.b / 3} <= set(numbers)
