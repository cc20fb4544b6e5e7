"""The quadruped's one body geometry (paper 003, Tab. 1): values and hip layout."""

from __future__ import annotations

import math

import numpy as np

from evomotion.sim.quadruped import geometry as g
from evomotion.sim.quadruped.model import QuadrupedSpec


def test_table_one_values() -> None:
    assert (g.BODY_A, g.BODY_B, g.L_MIN, g.L_MAX) == (2.5, 3.0, 1.0, 2.0)
    assert math.pi / 4 == g.SECTOR_HALF_WIDTH


def test_hips_at_the_corners_left_legs_facing_pi() -> None:
    hips = g.hip_positions(g.BODY_A, g.BODY_B)
    assert hips == ((-1.25, 1.5), (-1.25, -1.5), (1.25, -1.5), (1.25, 1.5))
    for (hx, _), side, nominal in zip(hips, g.LEG_SIDES, g.NOMINAL_ANGLES, strict=True):
        assert math.copysign(1.0, hx) == side == math.cos(nominal)


def test_spec_hips_are_the_geometry_in_metres() -> None:
    s = QuadrupedSpec()
    want = [[-0.5 * s.a * s.unit_m, 0.5 * s.b * s.unit_m, 0.0],
            [-0.5 * s.a * s.unit_m, -0.5 * s.b * s.unit_m, 0.0],
            [0.5 * s.a * s.unit_m, -0.5 * s.b * s.unit_m, 0.0],
            [0.5 * s.a * s.unit_m, 0.5 * s.b * s.unit_m, 0.0]]
    assert np.array_equal(s.hips_m(), np.array(want))  # the former formula, bit for bit
