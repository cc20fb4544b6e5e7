from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.run.stats import read_stats

sys.path.insert(0, str(Path(__file__).parent))
from toy_study import STUDY  # noqa: E402

DETERMINISTIC = ("generation", "evaluations", "best", "mean", "median", "min", "max", "std",
                 "best_so_far", "diversity", "failed")


def _same_results(d1: Path, d2: Path) -> None:
    s1, s2 = read_stats(d1 / "stats.csv"), read_stats(d2 / "stats.csv")
    for col in DETERMINISTIC:
        np.testing.assert_array_equal(s1[col], s2[col], err_msg=col)
    b1, b2 = json.loads((d1 / "best.json").read_text()), json.loads((d2 / "best.json").read_text())
    assert b1["genome"] == b2["genome"] and b1["fitness"] == b2["fitness"]


def test_failures_become_worst_and_are_logged(tmp_path):
    cfg = resolve_config(STUDY, None, ["run.generations=5"])
    res = run_study(STUDY, cfg, tmp_path, quiet=True)
    stats = read_stats(tmp_path / "stats.csv")
    assert stats["failed"].sum() > 0  # the toy problem fails on purpose
    log = (tmp_path / "log.txt").read_text()
    assert "simulated solver blow-up" in log or "non-finite" in log
    assert np.isfinite(res.best_fitness) and res.stop_reason == "generations"


def test_evaluators_give_identical_results(tmp_path):
    cfg_s = resolve_config(STUDY, None, ["run.generations=6"])
    cfg_p = resolve_config(STUDY, None, ["run.generations=6", "run.evaluator=process",
                                         "run.workers=2", "run.chunks_per_worker=3"])
    run_study(STUDY, cfg_s, tmp_path / "s", quiet=True)
    run_study(STUDY, cfg_p, tmp_path / "p", quiet=True)
    _same_results(tmp_path / "s", tmp_path / "p")


def test_resume_after_interrupt_is_bit_identical(tmp_path, monkeypatch):
    cfg = resolve_config(STUDY, None, ["run.generations=20", "run.checkpoint_every=4"])
    run_study(STUDY, cfg, tmp_path / "full", quiet=True)

    from evomotion.run import evaluators

    calls = {"n": 0}
    orig = evaluators.SerialEvaluator.__call__

    def interrupting(self, genomes):
        calls["n"] += 1
        if calls["n"] == 11:  # mid-run, between checkpoints
            raise KeyboardInterrupt
        return orig(self, genomes)

    monkeypatch.setattr(evaluators.SerialEvaluator, "__call__", interrupting)
    res = run_study(STUDY, cfg, tmp_path / "cut", quiet=True)
    assert res.stop_reason == "interrupted" and res.exit_code == 130
    monkeypatch.setattr(evaluators.SerialEvaluator, "__call__", orig)
    res2 = run_study(STUDY, cfg, tmp_path / "cut", quiet=True, resume=True)
    assert res2.stop_reason == "generations"
    _same_results(tmp_path / "full", tmp_path / "cut")


def test_resume_after_kill_9_is_bit_identical(tmp_path):
    overrides = ["run.generations=40", "run.checkpoint_every=3", "problem.sleep_s=0.05"]
    cfg = resolve_config(STUDY, None, overrides)
    run_study(STUDY, cfg, tmp_path / "full", quiet=True)
    out = tmp_path / "killed"
    code = (
        f"import sys; sys.path.insert(0, {str(Path(__file__).parent)!r})\n"
        "from toy_study import STUDY\n"
        "from evomotion.run.config import resolve_config\n"
        "from evomotion.run.runner import run_study\n"
        f"run_study(STUDY, resolve_config(STUDY, None, {overrides!r}), {str(out)!r}, quiet=True)\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", code])
    deadline = time.time() + 60
    while time.time() < deadline:
        ck = sorted((out / "checkpoints").glob("gen-*.json")) if out.exists() else []
        if ck and int(ck[-1].stem[4:]) >= 10:
            break
        time.sleep(0.02)
    time.sleep(0.07)  # land between checkpoints
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert not (out / "best.json").exists()  # it really died mid-run
    cfg2 = resolve_config(STUDY, None, overrides)
    run_study(STUDY, cfg2, out, quiet=True, resume=True)
    _same_results(tmp_path / "full", out)


@pytest.mark.parametrize("item,reason", [
    ("run.max_evaluations=100", "max_evaluations"),
    ("run.target=-5000", "target"),
    ("run.wall_seconds=1e-9", "wall_seconds"),
])
def test_stop_reasons(tmp_path, item, reason):
    cfg = resolve_config(STUDY, None, [item])
    res = run_study(STUDY, cfg, tmp_path, quiet=True)
    assert res.stop_reason == reason
    assert reason in (tmp_path / "log.txt").read_text()


def test_stagnation_stop(tmp_path):
    from evomotion.studies import get_study

    s = get_study("functions")
    cfg = resolve_config(s, None, ["problem.dim=2", "run.generations=500",
                                   "run.stagnation_generations=5", "run.stagnation_eps=1e-3"])
    res = run_study(s, cfg, tmp_path, quiet=True)
    assert res.stop_reason == "stagnation" and res.generation < 500


def test_run_folder_contents(tmp_path):
    cfg = resolve_config(STUDY, None, ["run.generations=3"])
    run_study(STUDY, cfg, tmp_path, quiet=True)
    for name in ("config.toml", "stats.csv", "best.json", "log.txt", "plots/fitness.png",
                 "plots/fitness.svg", "checkpoints/latest.json"):
        assert (tmp_path / name).exists(), name
    header = (tmp_path / "stats.csv").read_text().splitlines()[0].split(",")
    for col in ("generation", "evaluations", "best", "mean", "median", "min", "max", "std",
                "best_so_far", "wall_s", "evals_per_s", "diversity"):
        assert col in header


def test_resume_extends_finished_run_identically(tmp_path):
    from evomotion.errors import InputError

    cfg10 = resolve_config(STUDY, None, ["run.generations=10", "problem.raise_above=9"])
    cfg20 = resolve_config(STUDY, None, ["run.generations=20", "problem.raise_above=9"])
    run_study(STUDY, cfg20, tmp_path / "full", quiet=True)
    run_study(STUDY, cfg10, tmp_path / "ext", quiet=True)
    with pytest.raises(InputError, match="already finished"):
        run_study(STUDY, cfg10, tmp_path / "ext", quiet=True, resume=True)
    run_study(STUDY, cfg20, tmp_path / "ext", quiet=True, resume=True)
    _same_results(tmp_path / "full", tmp_path / "ext")
