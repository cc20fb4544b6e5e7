"""The walk engine (studies/humanoid_omniwalk/omni_gait.py): feet where the module doc puts
them (checked by the leg's forward kinematics), the travel per stance set by the command, the
hip yaw-pitch motor shared in mirror image."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.leg_ik import leg_fk
from evomotion.studies.humanoid_omniwalk.omni_gait import OmniGait, foot_offset, targets

COL = {j: i for i, j in enumerate(nao.JOINTS)}
LEFT = [COL[j] for j in nao.LEFT_LEG]
RIGHT = [COL[j] for j in nao.RIGHT_LEG]
FLAT = OmniGait(lean_rad=0.0)


def _ankle(q: np.ndarray, cols: list[int], left: bool) -> np.ndarray:
    return leg_fk(q[..., cols], left=left)[0]


def test_foot_offset_swings_forward_then_stands_back():
    p = np.arange(1000) / 1000
    u, lift = foot_offset(p, 0.4)
    assert u[0] == -0.5 and u[400] == 0.5 and np.isclose(u[-1], -0.5, atol=2e-3)
    assert np.all(np.diff(u[:400]) >= 0) and np.all(np.diff(u[400:]) <= 0)
    assert lift.max() == pytest.approx(1.0, abs=1e-4) and np.all(lift[400:] == 0)


@pytest.mark.parametrize("cmd", [(0.3, 0.0, 0.0), (0.0, 0.15, 0.0), (-0.15, 0.1, 0.0)])
def test_a_stance_foot_moves_back_by_the_command_times_its_stance(cmd):
    """Over the left foot's stance ((1 - w) T) its ankle moves by -command (1 - w) T in the
    torso frame (no yaw, no lean): the body walks at the command."""
    g, w = FLAT, FLAT.swing_fraction
    phases = np.array([w, 0.999999])
    q = targets(g, phases, np.tile(cmd, (2, 1)))
    a = _ankle(q, LEFT, True)
    dx, dy, _ = g.travel(np.array(cmd))
    np.testing.assert_allclose(a[1, :2] - a[0, :2], [-dx, -dy], atol=2e-4)


def test_zero_command_steps_in_place_symmetrically():
    """Left at phase p mirrors right at p + 1/2 (y negated); the sway moves both feet alike."""
    p = np.linspace(0, 1, 24, endpoint=False)
    q = targets(FLAT, p, np.zeros((24, 3)))
    ql = targets(FLAT, p + 0.5, np.zeros((24, 3)))
    left, right = _ankle(q, LEFT, True), _ankle(ql, RIGHT, False)
    np.testing.assert_allclose(left[:, [0, 2]], right[:, [0, 2]], atol=1e-9)
    sway = FLAT.sway_m * np.cos(2 * np.pi * (p - FLAT.swing_fraction / 2))
    np.testing.assert_allclose(left[:, 1] + right[:, 1], -sway - sway[(np.arange(24) + 12) % 24],
                               atol=1e-9)


def test_turning_yaws_the_feet_in_mirror_image_through_one_motor():
    p = np.linspace(0, 1, 24, endpoint=False)
    q = targets(FLAT, p, np.tile([0.0, 0.0, 1.0], (24, 1)))
    assert np.array_equal(q[:, COL["LHipYawPitch"]], q[:, COL["RHipYawPitch"]])
    assert np.ptp(q[:, COL["LHipYawPitch"]]) > 0.1
    still = targets(FLAT, p, np.zeros((24, 3)))
    assert np.abs(still[:, COL["LHipYawPitch"]]).max() < 1e-9


def test_targets_stay_in_the_nao_joint_ranges():
    from evomotion.sim.robots.nao.joint_limits import JOINT_RANGES

    rng = np.random.default_rng(0)
    cmd = rng.uniform([-1, -1, -3], [1, 1, 3], (200, 3))
    q = targets(OmniGait(), rng.uniform(0, 3, 200), cmd)
    lo, hi = np.array([JOINT_RANGES[j] for j in nao.JOINTS]).T
    assert np.all(q >= lo) and np.all(q <= hi) and np.isfinite(q).all()


def test_foot_offsets_move_each_foot_by_exactly_its_offset():
    """``foot_offsets`` (a footstep adjustment) moves each ankle by its own (x, y) in the walk
    frame, the other foot untouched; zero offsets are the plain engine, bit for bit."""
    p = np.array([0.1, 0.3, 0.6, 0.9])
    cmd = np.tile([0.2, 0.05, 0.0], (4, 1))
    plain = targets(FLAT, p, cmd)
    assert np.array_equal(targets(FLAT, p, cmd, np.zeros((4, 2, 2))), plain)
    off = np.zeros((4, 2, 2))
    off[:, 0] = [0.04, -0.02]  # the left foot only
    moved = targets(FLAT, p, cmd, off)
    np.testing.assert_allclose(_ankle(moved, LEFT, True) - _ankle(plain, LEFT, True),
                               np.tile([0.04, -0.02, 0.0], (4, 1)), atol=1e-9)
    np.testing.assert_array_equal(moved[:, RIGHT[1:]], plain[:, RIGHT[1:]])
