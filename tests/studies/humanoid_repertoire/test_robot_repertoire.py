"""humanoid-repertoire on another biped (``problem.robot``): the scaled step through the
numerical leg IK, measures equal to a replay of the exported motion, a short run whose
repertoire pick, export and walk-to use, and one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.studies.humanoid_repertoire import step
from evomotion.studies.humanoid_repertoire.problem import HumanoidRepertoireConfig, make_problem


@pytest.fixture(scope="module")
def op3():
    return make_problem(HumanoidRepertoireConfig(robot="op3", hold_s=1.0, threads=1))


def test_the_step_is_scaled_to_the_robot_and_starts_and_ends_in_its_ready_pose(op3):
    s = op3.steps
    assert 1.0 < s.scale < 1.4  # OP3 legs: a little longer than the NAO's
    i = step.INDEX
    np.testing.assert_allclose(op3.genome.upper[i["dx_m"]], step.UPPER[i["dx_m"]] * s.scale)
    np.testing.assert_allclose(op3.genome.upper[i["shift_s"]],
                               step.UPPER[i["shift_s"]] * np.sqrt(s.scale))
    np.testing.assert_allclose(op3.measure_spec.upper[:2], [0.15 * s.scale, 0.08 * s.scale])
    rng = np.random.default_rng(0)
    genomes = rng.uniform(op3.genome.lower, op3.genome.upper, (6, 8))
    poses, err = s.poses(genomes)
    for q in poses:
        np.testing.assert_allclose(q[0], op3.robot.pose, atol=1e-9)
        np.testing.assert_allclose(q[-1], op3.robot.pose, atol=1e-9)
    assert err.shape == (6,) and np.all(err >= 0)
    # the default (in-place) step: every key pose solved exactly
    assert s.poses(s.default[None])[1][0] < 1e-5


def test_a_forward_step_moves_the_feet_forward(op3):
    """The IK puts the lead sole where the plan says: half-way through, the left foot has
    moved dx forward in the torso's frame of the start."""
    g = op3.steps.default.copy()
    g[step.INDEX["dx_m"]] = 0.06
    q = op3.steps.poses(g[None])[0][0]
    leg = op3.steps.legs["left"]
    sole = leg.fk(q[:, leg.columns])[0]
    assert sole[-1, 0] - sole[0, 0] == pytest.approx(0.0, abs=1e-6)  # back under the torso
    assert sole[:, 0].max() - sole[0, 0] > 0.03  # ahead of the torso while stepping


def test_measures_are_what_a_replay_of_the_exported_motion_measures(op3):
    from evomotion.sim.play import play_motion

    g = op3.steps.default.copy()
    g[:3] = [0.04, 0.0, 0.15]
    ev = op3.evaluate(np.stack([op3.steps.default, g]))
    assert ev.measures.shape == (2, 3) and np.isfinite(ev.measures).all()
    assert set(op3.metric_names) <= set(ev.metrics) and "ik_error_m" in ev.metrics
    assert ev.metrics["fell"][0] == 0.0  # the in-place step stands
    # replayed for the problem's horizon (hold_s after the longest possible step)
    m = op3.motion(g)
    r = play_motion(op3.robot, m, hold_s=op3.horizon_s - m.duration_s)["summary"]
    end = int(np.ceil((m.duration_s + 1.0) / op3.dt))
    assert end <= op3.nstep
    np.testing.assert_allclose(ev.measures[1, :2], r["displacement_m"], atol=0.01)
    assert ev.measures[1, 0] > 0.02 and ev.measures[1, 2] > 3.0  # forward and to the left


def test_short_run_on_op3_writes_a_repertoire_that_pick_export_and_walk_to_use(tmp_path):
    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study
    from evomotion.sim.motion import read_motion
    from evomotion.studies import get_study
    from evomotion.studies.humanoid_repertoire.step_planning import pick, walk_to

    s = get_study("humanoid-repertoire")
    cfg = resolve_config(s, None, [*s.smoke, "problem.robot=op3", "run.generations=2",
                                   "problem.threads=1"])
    res = run_study(s, cfg, tmp_path, quiet=True)
    assert res.exit_code == 0
    index = json.loads((tmp_path / "repertoire" / "index.json").read_text())
    assert index["robot"] == "op3" and index["stepper"] == "numerical" and index["entries"]
    assert index["box"]["upper"][0] > 0.15  # scaled to the OP3
    assert not (tmp_path / "repertoire" / "ready.motion").exists()
    robot = make_problem(cfg.problem).robot
    for e in index["entries"]:
        m = read_motion(tmp_path / "repertoire" / e["file"], robot.joints)
        assert m.joints == robot.joints
    physics = json.loads((tmp_path / "physics.json").read_text())
    assert physics["robot"] == "op3"
    r = pick(tmp_path, 0.05, 0.0, 0.0)
    assert r["cell"] in [e["cell"] for e in index["entries"]]
    w = walk_to(tmp_path, 0.05, 0.0, 0.0, out=tmp_path / "chain.motion", hold_s=0.2)
    assert w["steps"] >= 1 and read_motion(tmp_path / "chain.motion", robot.joints)
    # the repertoire folder itself works too (its run folder holds the config)
    w2 = walk_to(tmp_path / "repertoire", 0.05, 0.0, 0.0, out=tmp_path / "c2.motion",
                 hold_s=0.2)
    assert w2["reached"] == w["reached"]
    with pytest.raises(Exception, match="unknown joint"):
        read_motion(tmp_path / "chain.motion")  # not NAO joints
    from typer.testing import CliRunner

    from evomotion.studies.humanoid_repertoire.study import cli

    out = CliRunner().invoke(cli, ["export", str(tmp_path)])
    assert out.exit_code == 0 and f"{len(index['entries'])} standing steps" in out.output
    from evomotion.studies.biped_kick.walk_play import walk

    with pytest.raises(InputError, match="robot 'op3'"):
        walk(None, tmp_path, None, None)


def test_a_robot_without_left_and_right_feet_is_one_line():
    pytest.importorskip("dm_control")
    with pytest.raises(InputError, match="left' and 'right"):
        make_problem(HumanoidRepertoireConfig(robot="dm-quadruped"))


def test_the_horizon_holds_the_longest_step_on_the_pose_grid(op3):
    """Phases are rounded to the 20 ms grid: the longest one may round up, and its hold
    must still fit (measured where a replay of its .motion measures it)."""
    g = op3.genome.upper.copy()
    g[step.INDEX["lead"]] = 1.0
    m = op3.motion(g)
    assert m.duration_s <= op3.steps.max_duration_s + 1e-12
    _, end = op3.controls(g[None])
    assert end[0] == int(np.ceil((m.duration_s + op3.cfg.hold_s) / op3.dt)) - 1 < op3.nstep


def test_a_copy_of_the_nao_spec_is_another_robot(tmp_path):
    """The repertoire of a copy of nao.toml (another path) is another robot's: generic step,
    walk-to plays it on the copy's model, the kick refuses it; old
    indexes (a NAO flag, or the robot's name only) read alike."""
    import shutil

    from evomotion.sim.repertoire import stepper_of
    from evomotion.sim.robots import spec_path

    copy = tmp_path / "my_nao.toml"
    shutil.copy(spec_path("nao"), copy)
    p = make_problem(HumanoidRepertoireConfig(robot=str(copy), threads=1))
    assert p.steps.name == "numerical" and p.robot.name == "nao"
    assert stepper_of({"robot": "nao"}) == "closed_form"
    assert stepper_of({"robot": "op3"}) == "numerical"
    assert stepper_of({"robot": "nao", "is_nao": False}) == "numerical"
    assert stepper_of({"robot": "nao", "is_nao": True}) == "closed_form"
    assert stepper_of({"robot": "nao", "stepper": "numerical"}) == "numerical"
    from evomotion.studies.humanoid_repertoire.problem import HumanoidRepertoireProblem

    assert type(p) is HumanoidRepertoireProblem  # one problem class, the robot a parameter


def test_the_nao_box_size_is_its_measure_spec():
    from evomotion.studies.humanoid_repertoire.problem import MEASURES
    from evomotion.studies.humanoid_repertoire.step_planning import NAO_BOX_SIZE, _box_size

    np.testing.assert_allclose(NAO_BOX_SIZE, MEASURES.upper - MEASURES.lower)
    np.testing.assert_allclose(_box_size({}), NAO_BOX_SIZE)
    np.testing.assert_allclose(_box_size({"box": {"lower": [0, 0, 0], "upper": [1, 2, 3]}}),
                               [1, 2, 3])
    np.testing.assert_allclose(_box_size({"box": {"lower": [0, 0], "upper": "x"}}),
                               NAO_BOX_SIZE)
