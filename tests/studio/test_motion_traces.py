"""The motion analysis under the 3D player (issue 35): angles, tilt, heights and foot contacts
of the recorded frames."""

from __future__ import annotations

import numpy as np

from evomotion.sim.robots import load_robot
from evomotion.studio import motion_traces as mt
from evomotion.studio.nao3d import load_scene_model, record_poses
from fixture_files import WEBOTS_MOTIONS

WAVE = WEBOTS_MOTIONS / "HandWave.motion"


def test_a_standing_wave_stands_on_both_feet_and_waves_an_arm():
    rec = record_poses(WAVE, fps=25, hold_s=0.5)
    model = load_scene_model("nao")
    tr = mt.traces(model, rec["frame_states"], rec["frame_ctrl"],
                   dict(load_robot("nao").spec.feet))
    later = slice(5, None)  # after the first frames' settling
    assert tr["contact"]["left"][later].mean() > 0.9 and tr["contact"]["right"][later].mean() > 0.9
    assert tr["tilt_deg"].max() < 10 and 0.25 < tr["com_m"][:, 2].mean() < 0.35
    assert 0.28 < tr["torso_z_m"].mean() < 0.36
    # the waving arm moves, the legs hardly
    span = {k: np.ptp(v) for k, v in tr["joints"].items()}
    assert max(span["RShoulderPitch"], span["RElbowRoll"]) > 20 and span["LKneePitch"] < 5
    t = np.asarray(rec["t_s"])
    series = mt.angle_series(tr, t)
    assert list(series)[0] == "torso tilt" and len(series["RElbowRoll"]) == len(t)
    support = mt.support_series(tr, t)
    assert [s["name"] for s in support][:2] == ["left foot on the floor",
                                                "right foot on the floor"]


def test_the_zmp_of_a_standing_robot_lies_under_it_near_its_centre_of_mass():
    rec = record_poses(WAVE, fps=25, hold_s=2.0)
    model = load_scene_model("nao")
    tr = mt.traces(model, rec["frame_states"], rec["frame_ctrl"],
                   dict(load_robot("nao").spec.feet))
    zmp = tr["zmp_m"]
    assert np.isfinite(zmp[5:]).all()
    # standing still after the wave (its last 0.5 s): the ZMP under the CoM (statics); while
    # the arms swing it moves a few cm (dynamics), measured up to 5 cm
    still = slice(-12, None)
    assert np.abs(zmp[still] - tr["com_m"][still, :2]).max() < 0.005
    assert np.abs(zmp[5:] - tr["com_m"][5:, :2]).max() > 0.01
    series = mt.balance_series(tr, np.asarray(rec["t_s"]))
    assert [s["name"] for s in series] == ["ZMP x (m)", "CoM x (m)", "ZMP y (m)", "CoM y (m)"]


def test_the_ball_on_the_kick_floor_is_not_the_robots_zmp():
    from evomotion.sim.zmp import floor_contacts

    model = load_scene_model("kick")
    rec = record_poses(WEBOTS_MOTIONS / "Shoot.motion", scene="kick", fps=10, hold_s=0.2)
    zmp = mt.traces(model, rec["frame_states"], rec["frame_ctrl"],
                    dict(load_robot("nao").spec.feet))["zmp_m"]
    assert np.isfinite(zmp[2:]).any()
    # the ball rests in front of the robot: its floor contact would pull the CoP forward
    import mujoco

    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, rec["frame_states"][3], mujoco.mjtState.mjSTATE_FULLPHYSICS)
    mujoco.mj_forward(model, data)
    floor = int(np.flatnonzero(model.geom_type == mujoco.mjtGeom.mjGEOM_PLANE)[0])
    everything = floor_contacts(model, data, floor)[0]
    assert len(everything) > len(floor_contacts(model, data, floor, {0})[0])

