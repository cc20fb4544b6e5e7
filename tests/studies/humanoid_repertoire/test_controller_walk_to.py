"""``walk-to`` with a humanoid-walk run: the controller walks the NAO closed loop to the
target (issue 34); the repertoire's A* chain stays the command for a repertoire run."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from evomotion.sim.walk_to_pose import command_limits, moved, soles, torso_pose


def _cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "evomotion.cli", "humanoid-repertoire",
                           "walk-to", *args], capture_output=True, text=True, cwd=cwd,
                          timeout=300)


def test_walk_to_with_a_controller_reports_the_closed_loop_walk(omniwalk_run, tmp_path):
    r = _cli(str(omniwalk_run), "--x", "0.3", "--y", "0.0", "--theta", "0", "--json",
             cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    assert res["controller"] == str(omniwalk_run) and isinstance(res["fell"], bool)
    assert res["duration_s"] >= res["walk_s"] > 0 or res["fell"]
    err = np.hypot(res["reached"]["x_m"] - 0.3, res["reached"]["y_m"])
    assert abs(err - res["position_error_m"]) < 1e-9
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_walk_to_walks_the_runs_robot(tmp_path):
    """An OP3 controller (a one-generation `--robot op3` run) walks the OP3, not the NAO."""
    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study
    from evomotion.studies import get_study
    from evomotion.studies.humanoid_repertoire.controller_walk_to import (
        controller_walk_to,
        run_robot,
    )

    s = get_study("humanoid-walk")
    out = tmp_path / "op3"
    run_study(s, resolve_config(s, None, [*s.smoke, "run.generations=1", "run.videos=false",
                                          "problem.robot='op3'"]), out, quiet=True)
    assert run_robot(out) == "op3"
    res = controller_walk_to(out, 0.1, 0.0, 0.0, hold_s=0.2, max_s=1.0)
    assert isinstance(res["fell"], bool) and 0 < res["duration_s"] < 3.0


@pytest.mark.parametrize("args,msg", [
    (["--x", "0.5", "--out", "w.motion"], "--out: a walk controller's walk is closed loop"),
    (["--x", "nan"], "--x"),
    (["--x", "0.5", "--video", "w.gif"], "expected a .mp4 path"),
])
def test_walk_to_with_a_controller_bad_input_is_one_line(omniwalk_run, tmp_path, args, msg):
    r = _cli(str(omniwalk_run), *args, cwd=tmp_path)
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode == 2 and len(lines) == 1 and msg in lines[0], r.stderr


def test_go_to_pose_helpers():
    poses = np.array([[1.0, 2.0, np.pi / 2]])
    assert np.allclose(moved(poses, np.array([0.1, 0.0])), [[1.0, 2.1, np.pi / 2]])

    class Player:
        command_ranges = {"vx": (-0.2, 0.45), "vy": (-0.2, 0.2), "yaw_rate": (-1.2, 1.2)}

    assert np.allclose(command_limits(Player, "x") / 0.8, [0.45, 0.2, 1.2, 0.2])
    Player.command_ranges = {"a": (0.0, 1.0)}
    with pytest.raises(Exception, match="command ranges of a walk"):
        command_limits(Player, "x")
    import mujoco

    from evomotion.sim.robots import load_robot

    m = load_robot("nao").model
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    feet = soles(d, ("l_sole_site", "r_sole_site"))
    assert abs(feet[2] - torso_pose(d)[2]) < 1e-6 and abs(feet[1] - d.qpos[1]) < 0.01
