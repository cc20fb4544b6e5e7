"""The humanoid-walk-open-loop study end to end (tiny budget): artifacts, exports, compare."""

import json
import subprocess
import sys

import numpy as np
import pytest
from typer.testing import CliRunner

from evomotion.cli import app
from evomotion.errors import InputError
from evomotion.sim.motion import read_motion
from evomotion.studies.humanoid_walk import compare, foot_gait
from evomotion.studies.humanoid_walk.walk_motion import whole_walk

runner = CliRunner()


def cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "evomotion.cli", *args], capture_output=True,
                          text=True, timeout=600)


@pytest.fixture(scope="module")
def walk_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("walk") / "run"
    res = runner.invoke(app, ["run", "humanoid-walk-open-loop", "--out", str(out), "--quiet",
                              "--set", "run.generations=1", "--set", "algorithm.pop_size=4",
                              "--set", "problem.walk_s=1.0", "--set", "problem.hold_s=0.3",
                              "--set", "problem.threads=1"])
    assert res.exit_code == 0, res.output
    return out


def test_run_writes_the_walk_and_its_parts(walk_run):
    best = json.loads((walk_run / "best.json").read_text())
    assert best["study"] == "humanoid-walk-open-loop" and set(foot_gait.NAMES) <= set(best["gait"])
    m = read_motion(walk_run / "best.motion")
    parts = [read_motion(walk_run / n) for n in ("walk_start.motion", "walk_cycle.motion",
                                                 "walk_stop.motion")]
    np.testing.assert_array_equal(parts[1].values[0], parts[1].values[-1])
    np.testing.assert_array_equal(m.values, whole_walk(np.array(best["genome"]), 1.0).values)
    assert best["motion"]["cycles"] >= 1
    replay = json.loads((walk_run / "best_replay.json").read_text())
    assert replay["fell"] is False and replay["speed_mps"] == pytest.approx(
        replay["displacement_m"][0] / replay["duration_s"])
    assert (walk_run / "best_naoqi.py").exists() and (walk_run / "best_keyframes.json").exists()


def test_compare_puts_the_walk_beside_webots(walk_run):
    rows = compare.compare(walk_run, hold_s=0.5)
    names = list(rows)
    assert names[0].startswith("evolved walk") and len(names) == 1 + len(compare.WEBOTS)
    table = compare.table(rows)
    assert "Webots TurnLeft40" in table and table.count("\n") == len(rows) + 1
    res = cli("humanoid-walk-open-loop", "compare", str(walk_run), "--json", "--hold", "0.5")
    assert res.returncode == 0, res.stderr
    assert set(json.loads(res.stdout)) == set(rows)


def test_compare_refuses_a_folder_without_a_walk(tmp_path):
    (tmp_path / "config.toml").write_text('study = "humanoid-walk-open-loop"\n')
    with pytest.raises(InputError, match="best.motion"):
        compare.walk_motion_path(tmp_path)
    res = cli("humanoid-walk-open-loop", "compare", str(tmp_path))
    assert res.returncode != 0 and "Traceback" not in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and "best.motion" in res.stderr
