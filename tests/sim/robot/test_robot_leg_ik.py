"""The numerical leg IK of sim/robot: forward kinematics agrees with MuJoCo's, the damped
least squares reach every reachable target, respect the joint ranges, and a robot without a
proper leg is a one-line error."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.sim.robot import load_robot
from evomotion.sim.robot.leg_ik import LegChain, rotation_vector, torso_frame_feet

ROBOTS = ["nao", "op3", pytest.param("dm-humanoid", marks=pytest.mark.skipif(
    __import__("importlib").util.find_spec("dm_control") is None, reason="needs dm-control"))]


@pytest.mark.parametrize("name", ROBOTS)
def test_forward_kinematics_is_mujocos(name):
    robot = load_robot(name)
    rng = np.random.default_rng(1)
    for foot in ("left", "right"):
        leg = LegChain(robot, foot, robot.pose)
        assert len(leg.joints) == 6
        q = rng.uniform(leg.lower, leg.upper, (4, len(leg.joints)))
        sole, rot, _, _ = leg.fk(q)
        for i in range(len(q)):
            pose = robot.pose.copy()
            pose[leg.columns] = q[i]
            want_p, want_r = torso_frame_feet(robot, pose)[foot]  # mj_kinematics
            np.testing.assert_allclose(sole[i], want_p, atol=1e-12)
            np.testing.assert_allclose(rot[i], want_r, atol=1e-12)
        ready = torso_frame_feet(robot, robot.pose)[foot]
        np.testing.assert_allclose(leg.fk(leg.ready[None])[0][0], ready[0], atol=1e-12)


@pytest.mark.parametrize("name", ROBOTS)
def test_ik_reaches_reachable_targets_within_the_ranges(name):
    """Targets made by FK of poses near the ready pose are reached (95 %: to 10 um and 1e-4
    rad; all: to 1 mm)."""
    robot = load_robot(name)
    leg = LegChain(robot, "left", robot.pose)
    rng = np.random.default_rng(2)
    span = 0.25 * (leg.upper - leg.lower)
    q_true = np.clip(leg.ready + rng.uniform(-1, 1, (300, 6)) * np.minimum(span, 0.3),
                     leg.lower, leg.upper)
    p, r, _, _ = leg.fk(q_true)
    q, e_pos, e_rot = leg.solve(p, r)
    assert np.all((q >= leg.lower) & (q <= leg.upper))
    assert np.quantile(e_pos, 0.95) < 1e-5 and np.quantile(e_rot, 0.95) < 1e-4
    assert e_pos.max() < 1e-3
    got_p, got_r, _, _ = leg.fk(q)
    np.testing.assert_allclose(np.linalg.norm(got_p - p, axis=1), e_pos, atol=1e-12)
    # an unreachable target: as near as the ranges allow, not NaN
    q, e_pos, _ = leg.solve(p[:1] + [0.0, 0.0, -5.0], r[:1])
    assert np.isfinite(q).all() and e_pos[0] > 1.0


def test_rotation_vector_of_known_rotations():
    angle = np.array([0.0, 0.3, -1.2, 3.0])
    axis = np.array([0.0, 0.6, 0.8])
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    r = np.eye(3) + np.sin(angle)[:, None, None] * k + \
        (1 - np.cos(angle))[:, None, None] * (k @ k)
    np.testing.assert_allclose(rotation_vector(r), angle[:, None] * axis, atol=1e-12)


def test_a_foot_without_leg_joints_is_one_line(tmp_path):
    """A spec whose 'feet' are the torso itself has no leg to solve."""
    robot = load_robot("op3")
    fake = type("R", (), {"model": robot.model, "joints": robot.joints, "state0": robot.state0,
                          "spec": type("S", (), {"torso": "body", "path": "x.toml",
                                                 "feet": {"left": "body",
                                                          "right": "body"}})()})()
    with pytest.raises(InputError, match="no leg joints"):
        LegChain(fake, "left", robot.pose)
