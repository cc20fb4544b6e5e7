"""The studio's 3D NAO: the model's own geometry, poses recorded from the physics replay."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from evomotion.sim.nao.motion import read_motion
from evomotion.sim.nao.replay import simulate_motion
from evomotion.studio.nao3d import geom_table, load_scene_model, record_poses

FIXTURES = Path(__file__).resolve().parents[3] / "shared" / "fixtures" / "webots-motions"


def test_every_body_with_visual_geometry_is_drawn():
    model = load_scene_model("nao")
    table = geom_table(model)
    visual = {int(model.geom_bodyid[i]) for i in range(model.ngeom)
              if model.geom_group[i] in (0, 1) and model.geom_bodyid[i] != 0}
    assert {g["body"] for g in table} == visual
    assert {g["type"] for g in table} <= {"box", "sphere", "capsule", "cylinder", "ellipsoid"}
    kick = geom_table(load_scene_model("kick"))
    assert any(g["type"] == "sphere" and abs(g["size"][0] - 0.05) < 1e-9 for g in kick)


def test_recorded_poses_are_the_replayed_simulation():
    path = FIXTURES / "HandWave.motion"
    rec = record_poses(path, fps=25, hold_s=0.5)
    T, B = len(rec["t_s"]), len(rec["bodies"])
    assert rec["pos"].shape == (T, B, 3) and rec["mat"].shape == (T, B, 3, 3)
    assert np.isfinite(rec["pos"]).all() and not rec["fell"]
    sim = simulate_motion(read_motion(path), hold_s=0.5)
    model = sim["model"]
    data = mujoco.MjData(model)
    k = T // 2
    step = int(round(rec["t_s"][k] / sim["dt"])) - 1
    data.qpos[:] = sim["qpos"][step]
    mujoco.mj_kinematics(model, data)
    np.testing.assert_allclose(rec["pos"][k], data.xpos[rec["bodies"]], atol=1e-12)
    np.testing.assert_allclose(rec["mat"][k].reshape(B, 9), data.xmat[rec["bodies"]],
                               atol=1e-12)


def test_the_ball_lies_still_when_the_motion_does_not_touch_it():
    rec = record_poses(FIXTURES / "HandWave.motion", scene="kick", fps=10, hold_s=0.2)
    model = load_scene_model("kick")
    ball = rec["bodies"].index(model.body("ball").id)
    drift = np.linalg.norm(rec["pos"][:, ball] - rec["pos"][0, ball], axis=1).max()
    assert drift < 0.01 and abs(rec["pos"][0, ball, 2] - 0.05) < 0.002
