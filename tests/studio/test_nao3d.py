"""The studio's 3D NAO: the model's own geometry, poses recorded from the physics replay."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.sim.motion import read_motion
from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.replay import motion_targets, simulate_motion
from evomotion.studio.nao3d import geom_table, load_scene_model, mesh_stl, record_poses
from fixture_files import WEBOTS_MOTIONS

FIXTURES = WEBOTS_MOTIONS
WAVE = FIXTURES / "HandWave.motion"  # 1.4 s, arms only


def test_every_body_with_visible_geometry_is_drawn_in_its_colours():
    model = load_scene_model("nao")
    table = geom_table(model)
    drawn = {int(model.geom_bodyid[i]) for i in range(model.ngeom)
             if model.geom_group[i] <= 2 and model.geom_type[i] != mujoco.mjtGeom.mjGEOM_PLANE}
    assert {g["body"] for g in table} == drawn and len(drawn) == 23
    assert all(model.geom_group[g["id"]] == 1 for g in table)  # no collision geom (group 3)
    assert {g["type"] for g in table} == {"box", "sphere", "capsule", "cylinder", "ellipsoid"}
    shell = model.mat_rgba[model.material("shell").id]
    assert sum(np.allclose(g["rgba"], shell) for g in table) >= 10  # material colours
    kick = load_scene_model("kick")
    ball = [g for g in geom_table(kick) if g["body"] == kick.body("ball").id]
    assert len(ball) == 1 and ball[0]["type"] == "sphere" and ball[0]["size"][0] == 0.05


def test_a_mesh_geom_is_drawn_from_its_vertices_and_faces():
    xml = """<mujoco><asset><mesh name="m" vertex="0 0 0 1 0 0 0 1 0 0 0 1"/></asset>
    <worldbody><body><freejoint/><geom type="mesh" mesh="m"/></body></worldbody></mujoco>"""
    (g,) = geom_table(mujoco.MjModel.from_xml_string(xml))
    assert g["type"] == "mesh" and g["vertices"].shape == (4, 3) and g["faces"].shape == (4, 3)
    stl = mesh_stl(g["vertices"], g["faces"])
    assert len(stl) == 84 + 50 * 4 and int.from_bytes(stl[80:84], "little") == 4
    normals = np.frombuffer(stl[84:], dtype=np.uint8).reshape(4, 50)[:, :12].copy()
    assert np.allclose(np.linalg.norm(normals.view("<f4"), axis=1), 1.0)


def test_the_recording_starts_at_the_initial_state():
    rec = record_poses(WAVE, fps=25, hold_s=0.5)
    T, G, B = len(rec["t_s"]), len(rec["geoms"]), len(rec["bodies"])
    assert rec["pos"].shape == (T, G, 3) and rec["mat"].shape == (T, G, 3, 3)
    assert rec["body_pos"].shape == (T, B, 3) and rec["body_mat"].shape == (T, B, 3, 3)
    assert T == 48 and rec["t_s"][0] == 0 and np.allclose(np.diff(rec["t_s"]), 0.04)
    assert np.isfinite(rec["pos"]).all() and np.isfinite(rec["mat"]).all()
    assert not rec["fell"] and rec["fall_time_s"] is None
    assert rec["duration_s"] == pytest.approx(1.9) and rec["motion_s"] == pytest.approx(1.4)
    model = load_scene_model("nao")
    first, _ = motion_targets(read_motion(WAVE), model.opt.timestep, 1)
    data = nao.initial_data(model, first)
    torso = model.body("torso").id
    mine = [i for i, g in enumerate(rec["geoms"]) if model.geom_bodyid[g] == torso]
    np.testing.assert_allclose(rec["pos"][0, mine], data.geom_xpos[rec["geoms"][mine]],
                               atol=1e-12)
    assert rec["pos"][0, mine, 2].min() > 0.25  # the torso's geoms, standing


def test_the_recording_is_the_replayed_simulation():
    rec = record_poses(WAVE, fps=25, hold_s=0.5)
    sim = simulate_motion(read_motion(WAVE), hold_s=0.5)
    model, dt = sim["model"], sim["dt"]
    data = mujoco.MjData(model)
    for k in (1, len(rec["t_s"]) // 2, len(rec["t_s"]) - 1):
        data.qpos[:] = sim["qpos"][int(round(rec["t_s"][k] / dt)) - 1]  # the state after a step
        mujoco.mj_kinematics(model, data)
        np.testing.assert_allclose(rec["pos"][k], data.geom_xpos[rec["geoms"]], atol=1e-12)
        np.testing.assert_allclose(rec["mat"][k].reshape(-1, 9), data.geom_xmat[rec["geoms"]],
                                   atol=1e-12)
        np.testing.assert_allclose(rec["body_pos"][k], data.xpos[rec["bodies"]], atol=1e-12)
    assert rec["body_pos"][-1, 0, 2] > 0.3  # the torso is still up after the wave


def test_the_ball_lies_still_on_the_floor_when_the_motion_does_not_touch_it():
    rec = record_poses(WAVE, scene="kick", fps=10, hold_s=0.2)
    model = load_scene_model("kick")
    ball = list(rec["bodies"]).index(model.body("ball").id)
    path = rec["body_pos"][:, ball]
    assert np.abs(path[:, 2] - 0.05).max() < 1e-3  # resting on the floor (radius 50 mm)
    assert np.linalg.norm(path[:, :2] - path[0, :2], axis=1).max() < 1e-3
    assert 0.1 < path[0, 0] < 0.3  # in front of the robot's right foot


def test_recordings_are_cached_read_only_and_scenes_checked():
    rec = record_poses(WAVE)
    assert record_poses(WAVE) is rec and not rec["pos"].flags.writeable
    with pytest.raises(InputError):
        record_poses(WAVE, scene="mars")


def test_another_robots_motion_plays_on_that_robot(tmp_path):
    """A run of another robot (problem.robot): its motions (its channels) play on it, from
    its initial state, the recorded poses its own replay's."""
    from evomotion.run.config import config_to_toml, resolve_config
    from evomotion.sim.motion import format_motion
    from evomotion.sim.play import play_motion
    from evomotion.sim.robots import load_robot
    from evomotion.studies import get_study
    from evomotion.studies.humanoid_repertoire.problem import (
        HumanoidRepertoireConfig,
        make_problem,
    )
    from evomotion.studio.views import robot_of, scene_of

    p = make_problem(HumanoidRepertoireConfig(robot="op3", threads=1))
    g = p.steps.default.copy()  # the in-place step: it stands
    path = tmp_path / "step.motion"
    path.write_text(format_motion(p.motion(g)))
    rec = record_poses(path, "robot:op3", fps=25.0, hold_s=0.5)
    robot = load_robot("op3")
    ref = play_motion(robot, p.motion(g), hold_s=0.5)
    assert not rec["fell"] and not ref["summary"]["fell"]
    torso = list(rec["bodies"]).index(robot.model.body("body").id)
    end = ref["qpos"][-1]
    assert np.allclose(rec["body_pos"][-1, torso, :2], end[:2], atol=0.01)
    assert len({g["body"] for g in geom_table(load_scene_model("robot:op3"))}) > 15
    s = get_study("humanoid-repertoire")
    for robot_name, scene in (("op3", "robot:op3"), ("nao", "nao"), ("", "nao")):
        run = tmp_path / f"run-{robot_name or 'default'}"
        run.mkdir()
        cfg = resolve_config(s, None, [f"problem.robot={robot_name!r}"] if robot_name else [])
        (run / "config.toml").write_text(config_to_toml(cfg))
        assert scene_of(run) == scene
        assert robot_of(run) == robot_name  # the drive view's robot ("": the NAO)
    assert scene_of(tmp_path / "nothing") == "nao" and robot_of(tmp_path / "nothing") is None
