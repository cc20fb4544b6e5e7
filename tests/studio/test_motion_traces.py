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
    tr = mt.traces(model, rec["qpos"], dict(load_robot("nao").spec.feet))
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
