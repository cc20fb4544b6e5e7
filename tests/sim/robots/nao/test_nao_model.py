import mujoco
import numpy as np
import pytest

from evomotion.sim.robots import nao
from evomotion.sim.rollout import BatchSimulator, fall_step, torso_track


@pytest.fixture(scope="module")
def model():
    return nao.load_model()


def test_total_mass_matches_published_v5_table(model):
    assert model.body_mass.sum() == pytest.approx(nao.TOTAL_MASS_KG, abs=0.002)
    assert 5.3 <= model.body_mass.sum() <= 5.5


def test_22_servos_in_paper_order(model):
    assert model.nu == 22
    assert tuple(model.actuator(i).name for i in range(model.nu)) == nao.JOINTS
    for name in nao.LEG_SERVOS:
        assert name in nao.JOINTS


def test_hip_yaw_pitch_axes_are_45_degrees(model):
    s = 1 / np.sqrt(2)
    np.testing.assert_allclose(model.joint("LHipYawPitch").axis, [0, s, -s], atol=1e-6)
    np.testing.assert_allclose(model.joint("RHipYawPitch").axis, [0, s, s], atol=1e-6)


@pytest.mark.parametrize("side", ["L", "R"])
def test_leg_lengths_match_published(model, side):
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    hip = data.body(f"{side}Thigh").xpos
    knee = data.body(f"{side}Tibia").xpos
    ankle = data.body(f"{side}AnklePitch").xpos
    sole = data.site(f"{side.lower()}_sole_site").xpos
    torso = data.body("torso").xpos
    assert np.linalg.norm(knee - hip) == pytest.approx(nao.THIGH_M, abs=1e-9)
    assert np.linalg.norm(ankle - knee) == pytest.approx(nao.TIBIA_M, abs=1e-9)
    assert ankle[2] - sole[2] == pytest.approx(nao.FOOT_HEIGHT_M, abs=1e-9)
    assert torso[2] - hip[2] == pytest.approx(nao.HIP_OFFSET_Z_M, abs=1e-9)
    assert abs(hip[1] - torso[1]) == pytest.approx(0.050, abs=1e-9)


def test_initial_pose_within_joint_ranges(model):
    rng = nao.joint_ranges(model)
    q = nao.pose_vector()
    assert np.all((q >= rng[:, 0]) & (q <= rng[:, 1]))


def test_stands_10_s_in_initial_pose(model):
    dt = model.opt.timestep
    nstep = int(round(10.0 / dt))
    ctrl = np.tile(nao.pose_vector(), (1, nstep, 1))
    with BatchSimulator(model, 1) as sim:
        states = sim.run(nao.initial_state(model), ctrl)
    track = torso_track(states)
    assert fall_step(track, 0.20, np.pi / 4)[0] == nstep
    assert track.xyz[0, -1, 2] > 0.29
    assert np.linalg.norm(track.xyz[0, -1, :2] - track.xyz[0, 0, :2]) < 0.01
    assert track.up_z[0].min() > np.cos(np.radians(5))
