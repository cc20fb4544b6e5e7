"""``evomotion biped-kick play``: kick file reading, aimed kick-point planning, the whole chain."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.errors import InputError
from evomotion.studies.biped_kick.motion import GENES, START
from evomotion.studies.biped_kick.planning import plan_aimed_kick
from evomotion.studies.biped_kick.play import DEFAULT_KICK, play, read_kick
from evomotion.studies.biped_kick.problem import KickConfig, KickProblem

X0 = [START[g[0]] for g in GENES]


def test_read_kick_default_run_folder_and_errors(tmp_path):
    g, src = read_kick(None)
    assert g.shape == (len(GENES),) and src == str(DEFAULT_KICK)
    (tmp_path / "best.json").write_text(json.dumps({"study": "biped-kick", "genome": X0}))
    (tmp_path / "config.toml").write_text('study = "biped-kick"\n')
    assert np.allclose(read_kick(tmp_path)[0], X0)
    for text, what in (("{", "JSON"), (json.dumps({"genome": [1, 2]}), "finite numbers"),
                       (json.dumps({"study": "arm-ik", "genome": X0}), "biped-kick"),
                       (json.dumps({"genome": [float("nan")] * len(GENES)}), "finite"),
                       (json.dumps({"genome": [True] * len(GENES)}), "finite numbers"),
                       (json.dumps({"genome": [0.0] * len(GENES)}), "gene shift_y_m in")):
        f = tmp_path / "bad.json"
        f.write_text(text)
        with pytest.raises(InputError, match=what) as e:
            read_kick(f)
        assert "bad.json" in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(InputError, match="no such file"):
        read_kick(tmp_path / "nothing")


def test_aimed_plan_puts_the_ball_where_the_kick_wants_it():
    def local(aims):
        return np.stack([np.full(len(aims), 0.16), 0.1 * aims], axis=1)

    ball, target = np.array([1.5, 0.5]), np.array([4.5, 0.0])
    for robot in (np.array([0.0, 0.0, 0.0]), np.array([2.5, 1.5, 3.0]), np.array([1.0, -1, 1.5])):
        plan = plan_aimed_kick(robot, ball, target, local, np.radians(30))
        x, y, psi = plan.pose
        c, s = np.cos(psi), np.sin(psi)
        d = ball - [x, y]
        assert np.allclose([c * d[0] + s * d[1], -s * d[0] + c * d[1]],
                           local(np.array([plan.aim_rad]))[0])
        # the kick direction (heading + aim) points at the target
        psi_t = np.arctan2(*(target - ball)[::-1])
        assert np.isclose(np.cos(psi + plan.aim_rad - psi_t), 1.0)
        assert abs(plan.aim_rad) <= np.radians(30) + 1e-12
        assert np.allclose(plan.control_points[0], robot[:2])
        assert np.allclose(plan.control_points[-1], [x, y])
    # behind the ball on the target line, facing the target: the straight kick is cheapest
    u = (target - ball) / np.linalg.norm(target - ball)
    robot = np.array([*(ball - 1.0 * u), np.arctan2(u[1], u[0])])
    assert abs(plan_aimed_kick(robot, ball, target, local, np.radians(30)).aim_rad) < 0.06


def test_play_reports_the_whole_chain(tmp_path):
    p = KickProblem(KickConfig(nthread=2))
    res = play(p, np.array(X0), np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.3]),
               np.array([3.0, 0.0]))
    for key in ("ball_rest_m", "target_error_m", "time_s", "fell", "walk", "aim_deg"):
        assert key in res
    assert "walking model" in res["walk"] and res["walk_time_s"] > 0 and res["kicked"]
    assert res["ball_placement_error_m"] < 1e-3  # placed exactly by the walking model
    assert res["time_s"] > res["walk_time_s"] + res["kick_time_s"] - 1e-9
    assert np.linalg.norm(np.subtract(res["ball_rest_m"], [1.0, 0.3])) > 0.1  # it was kicked


def test_the_kick_that_sees_the_ball_follows_it_and_takes_the_tables_command():
    """``seen_kick``: a ball in its place is kicked as evolved (no shift, no stretch, the aim);
    a ball 1 cm outboard (right) is followed towards it within the limits; with a table the
    command is the table's (a synthetic one: the ball goes aim + 500 deg/m x dy)."""
    from evomotion.studies.biped_kick.aim_table import AimTable, command
    from evomotion.studies.biped_kick.play import seen_kick

    p = KickProblem(KickConfig(nthread=2))
    g, _ = read_kick(None)
    aim = np.radians(-10.0)
    want = p.wanted_ball_xy(g[None], np.array([aim]))[0]
    a, g1, shift, rep = seen_kick(p, g, aim, want)
    assert a == aim and np.array_equal(g1, g) and not shift.any()
    assert rep["followed_fraction"] == 1.0 and rep["swing_stretch"] == 1.0
    a, g2, shift, rep = seen_kick(p, g, aim, want + [0.0, -0.01])
    assert rep["ball_offset_m"] == pytest.approx([0.0, -0.01])
    assert rep["followed_fraction"] > 0 and shift[1] < 0
    assert np.allclose(shift, rep["followed_fraction"] * np.array([0.0, -0.01]))
    aims, dx, dy = np.arange(-40.0, 40.1, 2.5), np.array([-0.02, 0.02]), np.linspace(-0.06,
                                                                                    0.06, 25)
    A, _, Y = np.meshgrid(aims, dx, dy, indexing="ij")
    table = AimTable(aims, dx, dy, A + 500.0 * Y, np.full(A.shape, 2.0),
                     p.cfg.adapt_max_stretch, p.cfg.adapt_foot_roll_rad)
    ball = want + [0.0, -0.01]
    a, _, _, rep = seen_kick(p, g, aim, ball, table)
    assert a == pytest.approx(np.radians(command(table, p, g, -10.0, ball[None])[0]))
    assert rep["command_deg"] > -8.0  # a ball to the right: aimed further left


def test_play_with_a_kick_that_sees_the_ball():
    """``play(follow=True)``: no tolerance centre (the plan puts the ball where the kick wants
    it); placed by the walking model, the ball lies in its place, is followed whole and kicked
    as evolved."""
    p = KickProblem(KickConfig(nthread=2))
    g, _ = read_kick(None)
    res = play(p, g, np.zeros(3), np.array([1.0, 0.3]), np.array([3.0, 0.0]), follow=True)
    assert res["ball_tolerant_offset_m"] == 0.0 and res["kicked"] and not res["fell"]
    assert np.hypot(*res["ball_offset_m"]) < 1e-3 and res["followed_fraction"] == 1.0
    assert res["swing_stretch"] == 1.0 and res["command_deg"] == pytest.approx(res["aim_deg"])
    assert res["target_error_m"] < 0.5


def _cli(*args, cwd):
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "evomotion.cli", "biped-kick", "play", *args],
                          capture_output=True, text=True, cwd=cwd, timeout=300)


@pytest.mark.parametrize("args,msg", [
    (["--ball", "nan", "0"], "--ball: expected finite"),
    (["--ball", "1", "0", "--target", "1", "0"], "--target: expected at least 0.1 m"),
    (["--kick", "missing"], "no such file"),
    (["--video", "out.gif"], "expected a .mp4 path"),
    (["--walk", "missing"], "--walk missing"),
    (["--robot", "1.4", "0.45", "0"], "at least 0.3 m from the ball"),
    (["--video", "nofolder/out.mp4"], "does not exist"),
    (["--table", "missing.json"], "missing.json"),
    (["--blind", "--table", "missing.json"], "drop --blind or --table"),
])
def test_play_bad_input_is_one_line(tmp_path, args, msg):
    r = _cli(*args, cwd=tmp_path)
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode == 2 and len(lines) == 1 and msg in lines[0], r.stderr


def test_play_json(tmp_path):
    """By default the shipped walk controller walks the approach (simulated); ``--walk model``
    places the robot with the walking model."""
    r = _cli("--ball", "1.2", "0.4", "--target", "3", "0", "--json", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    assert {"ball_rest_m", "target_error_m", "time_s", "fell", "time_to_kick_s"} <= set(res)
    assert res["walk"].startswith("controller") and "default_walk" in res["walk"]
    assert not res["fell"] and res["walk_reached"] and res["walk_position_error_m"] < 0.04
    r = _cli("--ball", "1.2", "0.4", "--target", "3", "0", "--json", "--walk", "model",
             cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "walking model" in json.loads(r.stdout)["walk"]


def test_play_takes_an_aim_table_of_the_same_timing(tmp_path):
    """``--table``: the kick's command from that table (a synthetic one here); a table measured
    with another ``adapt_max_stretch`` or ``adapt_foot_roll_rad`` is one line before anything
    is simulated."""
    import dataclasses

    from evomotion.studies.biped_kick import aim_table

    aims, dx, dy = np.arange(-40.0, 40.1, 2.5), np.array([-0.02, 0.02]), np.linspace(-0.06,
                                                                                    0.06, 25)
    A, _, Y = np.meshgrid(aims, dx, dy, indexing="ij")
    table = aim_table.AimTable(aims, dx, dy, A + 300.0 * Y, np.full(A.shape, 2.0),
                               KickConfig().adapt_max_stretch,
                               KickConfig().adapt_foot_roll_rad)
    aim_table.write(tmp_path / "t.json", table)
    r = _cli("--ball", "1.2", "0.4", "--target", "3", "0", "--walk", "model", "--table",
             "t.json", "--json", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    assert res["kicked"] and "command_deg" in res and res["followed_fraction"] > 0
    with pytest.raises(InputError, match="follow=True"):
        play(KickProblem(KickConfig(nthread=1)), read_kick(None)[0], np.zeros(3),
             np.array([1.2, 0.4]), np.array([3.0, 0.0]), follow=False, table=table)
    aim_table.write(tmp_path / "old.json", dataclasses.replace(table, max_stretch=1.0))
    r = _cli("--table", "old.json", cwd=tmp_path)
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode == 2 and len(lines) == 1 and "adapt_max_stretch = 1" in lines[0]
    aim_table.write(tmp_path / "level.json", dataclasses.replace(table, foot_roll_rad=0.0))
    r = _cli("--table", "level.json", cwd=tmp_path)
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode == 2 and len(lines) == 1 and "adapt_foot_roll_rad = 0" in lines[0]


def test_the_shipped_kick_alone_stays_up():
    """``evomotion replay`` of the shipped kick's motion (no ball): the robot does not fall;
    nor with the left-foot kick the run exports."""
    from evomotion.sim.robots.nao.mirror import mirror_targets
    from evomotion.sim.robots.nao.replay import simulate_motion
    from evomotion.studies.biped_kick.artifacts import left_foot
    from evomotion.studies.biped_kick.motion import kick_motion

    g, _ = read_kick(None)
    for aim in (-30, 0, 30):
        assert simulate_motion(kick_motion(g, np.radians(aim)), hold_s=1.0)["summary"][
            "fell"] is False
    # the exported left-foot kick (kicks/left_aim_+30.motion) too
    left = left_foot(kick_motion(g, np.radians(-30)), mirror_targets)
    assert simulate_motion(left, hold_s=1.0)["summary"]["fell"] is False


def test_play_walks_with_a_repertoire_in_the_same_simulation(tmp_path):
    """A small repertoire (a 3-generation run) carries the robot towards the stand pose; the
    kick is then played from where it really stands."""
    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study
    from evomotion.studies import get_study

    s = get_study("humanoid-repertoire")
    cfg = resolve_config(s, None, list(s.smoke) + ["run.generations=3"])
    assert run_study(s, cfg, tmp_path, quiet=True).exit_code == 0
    p = KickProblem(KickConfig(nthread=2))
    g, _ = read_kick(None)
    res = play(p, g, np.array([0.0, 0.0, 0.0]), np.array([0.45, 0.05]), np.array([3.0, 0.0]),
               repertoire=tmp_path)
    assert "repertoire" in res["walk"] and res["walk_steps"] >= 0
    assert res["walk_time_s"] > 0.6  # at least the ready motion and back, simulated
    assert isinstance(res["fell"], bool) and (res["kicked"] or res["fell"])
    if res["kicked"]:
        assert np.isfinite(res["ball_placement_error_m"])
    else:  # fell while walking: no kick, the ball where it was
        assert res["target_error_m"] is None


def test_a_broken_repertoire_is_refused_before_walking(tmp_path):
    from evomotion.sim.repertoire import read_index

    rep = tmp_path / "repertoire"
    rep.mkdir()
    (tmp_path / "config.toml").write_text('study = "humanoid-repertoire"\n')
    entry = {"file": "cell-0001.motion", "cell": 1, "objective": -1.0,
             "measured": {"dx_m": "0.1", "dy_m": 0.0, "dtheta_deg": 0.0}}
    (rep / "index.json").write_text(json.dumps({"entries": [entry]}))
    with pytest.raises(InputError, match="dx_m"):
        read_index(tmp_path)
    entry["measured"]["dx_m"] = 0.1
    (rep / "index.json").write_text(json.dumps({"entries": [entry]}))
    p = KickProblem(KickConfig(nthread=1))
    with pytest.raises(InputError, match="no such file"):
        play(p, np.array(X0), np.zeros(3), np.array([1.0, 0.0]), np.array([3.0, 0.0]),
             repertoire=tmp_path)
    f = tmp_path / "file"
    f.write_text("x")
    with pytest.raises(InputError, match="cannot be read|no such file"):
        read_index(f)


@settings(max_examples=60, deadline=None)
@given(data=st.binary(max_size=300) | st.builds(
    lambda g, extra: json.dumps({"study": "biped-kick", "genome": g, **extra}).encode(),
    st.lists(st.floats(allow_nan=True, allow_infinity=True) | st.integers() | st.booleans()
             | st.text(max_size=3), max_size=len(GENES) + 1),
    st.dictionaries(st.text(max_size=4), st.integers(), max_size=2)))
def test_read_kick_accepts_or_one_line_error(data):
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        f = Path(d) / "best.json"
        f.write_bytes(data)
        try:
            g, _ = read_kick(f)
        except InputError as e:
            assert "\n" not in str(e) and str(e).startswith(str(f))
            return
        lo = np.array([x[1] for x in GENES])
        hi = np.array([x[2] for x in GENES])
        assert g.shape == (len(GENES),) and np.all((g >= lo) & (g <= hi))


def test_the_kick_does_not_depend_on_the_robots_heading_in_the_world():
    """Elliptic friction cones: the same kick from the robot turned 0 and 45 deg sends the ball
    in the same direction relative to the robot (pyramidal cones did not: +13.7 deg at 21)."""
    from evomotion.sim.robots import nao
    from evomotion.sim.rollout import interpolate_controls
    from evomotion.studies.biped_kick import scene
    from evomotion.studies.biped_kick.motion import (
        SETTLE_S,
        execution_time_s,
        joint_targets,
        key_times,
    )
    from evomotion.studies.biped_kick.play import field_state

    p = KickProblem(KickConfig(nthread=2))
    g, _ = read_kick(None)
    root0 = nao.state_qpos(p.model, nao.initial_state(p.model), nao.ROOT_JOINT, 2)
    local = p.ball_xy(g[None], np.zeros(1))[0] - root0
    kt = key_times(g[None])
    n = int((SETTLE_S + execution_time_s(g[None])[0] + 0.4) / p.dt)
    ctrl = interpolate_controls(kt, joint_targets(g[None], kt, 0.0)[0], p.dt, n)
    dirs = []
    for psi in (0.0, np.radians(45)):
        c, s = np.cos(psi), np.sin(psi)
        ball = np.array([c * local[0] - s * local[1], s * local[0] + c * local[1]])
        end = p.sim.run(field_state(p, np.array([0.0, 0.0, psi]), ball), ctrl[None])[0, -1]
        d = nao.state_qpos(p.model, end, scene.BALL_JOINT, 2) - ball
        assert np.linalg.norm(d) > 0.1
        dirs.append(np.degrees(np.arctan2(d[1], d[0]) - psi))
    assert abs(dirs[0] - dirs[1]) < 1.0


def test_go_to_pose_command_faces_the_goal_far_and_corrects_near():
    from evomotion.sim.walk_to_pose import FAR_M, command_to

    vmax = np.array([0.36, 0.16, 0.96, 0.16])
    far = command_to(np.zeros(3), np.array([2.0, 2.0, 0.0]), vmax)
    assert far[1] == 0.0 and far[2] > 0 and 0 <= far[0] <= vmax[0]  # turns left, walks on
    ahead = command_to(np.zeros(3), np.array([2.0, 0.0, 1.0]), vmax)
    assert np.allclose(ahead, [vmax[0], 0.0, 0.0])  # far: the goal heading waits
    near = command_to(np.array([1.0, 1.0, np.pi / 2]),
                      np.array([1.0 + 0.5 * FAR_M, 1.0, np.pi / 2 - 0.1]), vmax)
    assert near[0] == 0.0 or abs(near[0]) < 1e-12
    assert near[1] < 0 and near[2] < 0  # the goal lies to its right; turn clockwise
    assert np.all(np.abs(command_to(np.zeros(3), np.array([0.2, -0.3, 3.0]), vmax)[1:])
                  <= vmax[1:3])


def test_play_walks_with_a_walk_controller_in_the_same_simulation(omniwalk_run):
    """``play --walk`` with a humanoid-walk run: its exported controller walks the robot
    in the kick scene (stance, closed-loop walk, crouch), then the kick is played from where
    it stands; the video's frames cover the whole simulation."""
    from evomotion.studies.biped_kick.controller_walk import CROUCH_S, SETTLE_S, STANCE_S
    from evomotion.studies.biped_kick.play import walk_kind

    assert walk_kind(omniwalk_run) == "controller"
    p = KickProblem(KickConfig(nthread=1))
    g, _ = read_kick(None)
    res = play(p, g, np.zeros(3), np.array([0.9, 0.1]), np.array([3.5, 0.0]),
               repertoire=omniwalk_run)
    assert res["walk"].startswith("controller") and "simulated" in res["walk"]
    assert res["walk_time_s"] >= STANCE_S + CROUCH_S + SETTLE_S - 1e-9 or res["fell"]
    assert isinstance(res["fell"], bool) and (res["kicked"] or res["fell"])
    if res["kicked"]:
        assert res["time_to_kick_s"] > res["walk_time_s"]
        assert np.isfinite(res["walk_position_error_m"])


def test_a_walk_folder_of_another_study_or_a_broken_controller_is_one_line(omniwalk_run,
                                                                          tmp_path):
    import shutil

    bad = tmp_path / "walk"
    shutil.copytree(omniwalk_run, bad, ignore=shutil.ignore_patterns("checkpoints"))
    info = json.loads((bad / "policy.json").read_text())
    info["joints"][0] = "NoSuchJoint"
    (bad / "policy.json").write_text(json.dumps(info))
    r = _cli("--walk", str(bad), cwd=tmp_path)
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode == 2 and len(lines) == 1 and "NoSuchJoint" in lines[0], r.stderr
    (bad / "policy.json").write_text("[1, 2]")
    r = _cli("--walk", str(bad), cwd=tmp_path)
    assert r.returncode == 2 and "policy.json" in r.stderr and "Traceback" not in r.stderr
    (bad / "config.toml").write_text('study = "arm-ik"\n')
    r = _cli("--walk", str(bad), cwd=tmp_path)
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode == 2 and len(lines) == 1 and "a arm-ik run, expected a " \
        "humanoid-walk run" in lines[0], r.stderr


def test_a_stop_waits_for_as_much_double_support_as_the_gait_has():
    """The stop waits SETTLED_STEPS periods of double support beyond the first, or fewer for a
    gait whose double support lasted less over the last two periods (a mirror-symmetric walk's
    one period: it hovered until max_s and missed every play)."""
    from evomotion.sim.walk_to_pose import SETTLED_STEPS, settle_periods

    assert SETTLED_STEPS == 1
    assert settle_periods([1, 2, 3, 0, 0, 1, 2, 0, 0, 1]) == 1  # two periods and more
    assert settle_periods([0, 1, 0, 0, 1, 0, 0, 1]) == 0  # one period only
    assert settle_periods([1, 2, 3, 4]) == 1  # standing, no step yet
