"""NAO leg IK round trip against MuJoCo forward kinematics of the NAO model."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.leg_ik import leg_fk, leg_ik, rot_y

LEG = {True: ("LHipYawPitch", "LHipRoll", "LHipPitch", "LKneePitch", "LAnklePitch",
              "LAnkleRoll"),
       False: ("RHipYawPitch", "RHipRoll", "RHipPitch", "RKneePitch", "RAnklePitch",
               "RAnkleRoll")}


def mujoco_fk(model, data, names, q):
    """Ankle position and foot rotation in the torso frame from MuJoCo."""
    data.qpos[:] = model.qpos0
    for n, v in zip(names, q, strict=True):
        data.joint(n).qpos = v
    mujoco.mj_kinematics(model, data)
    torso, foot = data.body("torso"), data.body("LFoot" if names[0][0] == "L" else "RFoot")
    Rt = torso.xmat.reshape(3, 3)
    return Rt.T @ (foot.xpos - torso.xpos), Rt.T @ foot.xmat.reshape(3, 3)


@pytest.mark.parametrize("left", [True, False])
def test_ik_round_trip_against_mujoco_fk(left):
    model = nao.load_model()
    data = mujoco.MjData(model)
    rng = np.random.default_rng(1 if left else 2)
    lim = np.array([model.joint(n).range for n in LEG[left]])
    lim[3, 0] = max(lim[3, 0], 0.05)  # knee bent: the straight leg is singular
    q_true = rng.uniform(lim[:, 0], lim[:, 1], size=(400, 6))
    poses = [mujoco_fk(model, data, LEG[left], q) for q in q_true]
    p = np.array([a for a, _ in poses])
    R = np.array([b for _, b in poses])
    q_ik = leg_ik(p, R, left)  # one vectorised call for all poses
    back = [mujoco_fk(model, data, LEG[left], q) for q in q_ik]
    pos_err = np.max(np.linalg.norm(np.array([a for a, _ in back]) - p, axis=1))
    rot_err = np.max(np.abs(np.array([b for _, b in back]) - R))
    assert pos_err < 1e-3  # issue: < 1 mm; measured ~1e-16 m
    assert pos_err < 1e-9 and rot_err < 1e-9
    assert np.max(np.abs(q_ik - q_true)) < 1e-9  # unique on the knee >= 0 branch


def test_own_fk_equals_mujoco_fk():
    model = nao.load_model()
    data = mujoco.MjData(model)
    q = np.array([0.2, 0.1, -0.5, 1.0, -0.4, 0.05])
    p_mj, R_mj = mujoco_fk(model, data, LEG[True], q)
    p, R = leg_fk(q, left=True)
    assert np.allclose(p, p_mj, atol=1e-12) and np.allclose(R, R_mj, atol=1e-12)


def test_flat_foot_under_hip_needs_no_yaw():
    p = np.array([[0.02, 0.05, -0.30], [-0.03, -0.05, -0.28]])
    q_left = leg_ik(p[0], np.eye(3), True)
    q_right = leg_ik(p[1], rot_y(0.2), False)
    assert abs(q_left[0]) < 1e-12 and abs(q_right[0]) < 1e-12
    assert np.allclose(leg_fk(q_right, False)[0], p[1], atol=1e-12)
