"""The receding-horizon walker through the run loop: files, resume after Ctrl-C and kill -9,
one-line errors, ``check`` and ``simulate`` on a run folder."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.run.config import resolve_config
from evomotion.run.faults import fault_at
from evomotion.run.runner import EXIT_INTERRUPTED, run_study
from evomotion.run.stats import read_stats
from evomotion.studies import get_study

TINY = Path(__file__).parents[1] / "data" / "tiny.world"
SETS = [f"problem.world='{TINY}'", "algorithm.name=receding", "run.checkpoint_every=2",
        "run.seed=4", "problem.gif_max_frames=4"]
TIMED = {"wall_s", "evals_per_s", "plan_ms"}


def _same(d1: Path, d2: Path) -> None:
    s1, s2 = read_stats(d1 / "stats.csv"), read_stats(d2 / "stats.csv")
    assert list(s1) == list(s2)
    for col in s1:
        if col not in TIMED:
            np.testing.assert_array_equal(s1[col], s2[col], err_msg=col)
    m1, m2 = (json.loads((d / "mission.json").read_text()) for d in (d1, d2))
    assert m1["states"] == m2["states"] and m1["world"] == m2["world"]


@pytest.fixture(scope="module")
def full(tmp_path_factory):
    out = tmp_path_factory.mktemp("full")
    s = get_study("quadruped-plan")
    res = run_study(s, resolve_config(s, None, SETS), out, quiet=True)
    return out, res


def test_a_walk_writes_the_run_folder(full):
    out, res = full
    assert res.stop_reason == "reached" and res.exit_code == 0
    for name in ("mission.json", "plan.png", "plan.gif", "stats.csv", "best.json"):
        assert (out / name).stat().st_size > 0, name
    best = json.loads((out / "best.json").read_text())
    assert best["reached"] and best["transitions"] == best["fitness"] > 0
    stats = read_stats(out / "stats.csv")
    assert list(stats)[-4:] == ["transitions", "replans", "plan_ms", "events"]
    log = (out / "log.txt").read_text()
    assert "checker: ok" in log and "receding-horizon walk in tiny: reached" in log


def test_ctrl_c_then_resume_is_bit_identical(full, tmp_path):
    s = get_study("quadruped-plan")
    cfg = resolve_config(s, None, SETS)
    with fault_at(3, "interrupt"):
        cut = run_study(s, cfg, tmp_path / "cut", quiet=True)
    assert cut.stop_reason == "interrupted" and cut.exit_code == EXIT_INTERRUPTED
    run_study(s, cfg, tmp_path / "cut", quiet=True, resume=True)
    _same(full[0], tmp_path / "cut")


KILLER = textwrap.dedent("""
    import sys
    from evomotion.run.config import resolve_config
    from evomotion.run.faults import fault_at
    from evomotion.run.runner import run_study
    from evomotion.studies import get_study
    s = get_study("quadruped-plan")
    with fault_at(int(sys.argv[2]), "sigkill"):
        run_study(s, resolve_config(s, None, sys.argv[3:]), sys.argv[1], quiet=True)
""")


def test_kill_9_then_resume_is_bit_identical(full, tmp_path):
    out = tmp_path / "killed"
    out.mkdir()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    r = subprocess.run([sys.executable, "-c", KILLER, str(out), "5", *SETS], env=env,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == -9, r.stderr
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "resume", str(out), "-q"],
                       env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    _same(full[0], out)


def _cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "evomotion.cli", *args], capture_output=True,
                          text=True, timeout=600, cwd=cwd)


def test_check_and_simulate_accept_the_run_folder(full):
    out = full[0]
    r = _cli("quadruped-plan", "check", str(out))
    assert r.returncode == 0 and "mission.json: ok" in r.stdout, r.stderr
    r = _cli("quadruped-plan", "simulate", str(out / "mission.json"), "--json")
    assert "Traceback" not in r.stderr
    res = json.loads(r.stdout)
    assert r.returncode == (0 if res["body_up"] else 1)
    assert res["steps"] > 0 and res["final_position_error_m"] is not None


@pytest.mark.parametrize(("sets", "words"), [
    (["algorithm.name=receding"], "needs a world"),
    (["problem.world=moon", "algorithm.name=receding"], "unknown world 'moon'"),
    (["problem.world=gaps", "problem.start_x=1.0"], "problem.start_x: the world file"),
    (["problem.world=gaps", "algorithm.name=receding", "algorithm.planner=dfs"],
     "algorithm.planner: expected one of anytime, best-first"),
    (["problem.world=gaps", "algorithm.name=receding", "algorithm.slip_probability=2"],
     "algorithm.slip_probability"),
])
def test_bad_settings_are_one_line_errors(sets, words, tmp_path):
    s = get_study("quadruped-plan")
    with pytest.raises(InputError, match=words):
        cfg = resolve_config(s, None, sets)
        run_study(s, cfg, tmp_path / "x", quiet=True)
    r = _cli("run", "quadruped-plan", *[a for kv in sets for a in ("--set", kv)], "--out",
             str(tmp_path / "y"), "-q")
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "Traceback" not in r.stderr
