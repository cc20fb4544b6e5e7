"""The numerical leg IK of sim/robot: forward kinematics agrees with MuJoCo's, the damped
least squares reach every reachable target, respect the joint ranges, and a robot without a
proper leg is a one-line error."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.sim.leg_ik import LegChain, rotation_vector, torso_frame_feet
from evomotion.sim.robots import load_robot

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


TOY = """<mujoco model="toy">
  <compiler angle="radian"/>
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <body name="torso" pos="0 0 0.6">
      <freejoint name="root"/>
      <geom type="box" size="0.05 0.1 0.1" mass="2"/>
      {legs}
    </body>
  </worldbody>
  <actuator>{servos}</actuator>
</mujoco>"""
LEG = """<body name="{s}thigh" pos="0 {y} -0.1">
  <joint name="{s}_hip_r" axis="1 0 0" range="-0.5 0.5"/>
  <joint name="{s}_hip_p" axis="0 1 0" range="-1 1"/>
  <geom type="capsule" fromto="0 0 0 0 0 -0.2" size="0.02" mass="0.5"/>
  <body name="{s}shin" pos="0 0 -0.2">
    <joint name="{s}_knee" axis="0 1 0" range="-0.2 2" ref="{ref}"/>
    <geom type="capsule" fromto="0 0 0 0 0 -0.2" size="0.02" mass="0.3"/>
    <body name="{s}foot" pos="0 0 -0.2">
      <joint name="{s}_ank_p" axis="0 1 0" range="-1 1"/>
      <joint name="{s}_ank_r" axis="1 0 0" range="-0.5 0.5"/>
      <geom type="box" pos="0.02 0 -0.02" size="0.06 0.03 0.01" mass="0.2"/>
    </body>
  </body>
</body>"""


def test_a_joint_reference_angle_is_kept(tmp_path):
    """MuJoCo turns a hinge by its angle less its ``ref``: the FK does too (a knee with
    ref = 0.3 on one leg), and the ready pose's feet are the IK's fixed point."""
    legs = LEG.format(s="l", y=0.06, ref=0.3) + LEG.format(s="r", y=-0.06, ref=0.0)
    joints = [f"{s}_{j}" for s in "lr" for j in ("hip_r", "hip_p", "knee", "ank_p", "ank_r")]
    servos = "".join(f'<position joint="{j}" kp="50" ctrlrange="-0.2 1"/>' for j in joints)
    (tmp_path / "toy.xml").write_text(TOY.format(legs=legs, servos=servos))
    (tmp_path / "toy.toml").write_text(
        '[robot]\nname = "toy"\nmjcf = "toy.xml"\ntorso = "torso"\n\n'
        '[feet]\nleft = "lfoot"\nright = "rfoot"\n\n[fall]\nheight_m = 0.2\n\n'
        '[pose]\nl_knee = 0.4\nr_knee = 0.4\n')
    from evomotion.sim.robots import build_robot, read_spec

    robot = build_robot(read_spec(tmp_path / "toy.toml"))
    rng = np.random.default_rng(4)
    for foot in ("left", "right"):
        leg = LegChain(robot, foot, robot.pose)
        q = rng.uniform(leg.lower, leg.upper, (3, len(leg.joints)))
        sole, rot, _, _ = leg.fk(q)
        for i in range(3):
            pose = robot.pose.copy()
            pose[leg.columns] = q[i]
            want_p, want_r = torso_frame_feet(robot, pose)[foot]
            np.testing.assert_allclose(sole[i], want_p, atol=1e-12)
            np.testing.assert_allclose(rot[i], want_r, atol=1e-12)
        p0, r0 = torso_frame_feet(robot, robot.pose)[foot]
        q0, err, _ = leg.solve(p0[None], r0[None])
        np.testing.assert_allclose(q0[0], leg.ready, atol=1e-9)
        assert err[0] < 1e-9
