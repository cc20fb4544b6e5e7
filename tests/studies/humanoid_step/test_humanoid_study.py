import json

import numpy as np

from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.sim.motion import format_motion, read_motion
from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.replay import replay
from evomotion.studies import get_study
from evomotion.studies.humanoid_step.artifacts import genome_motion
from evomotion.studies.humanoid_step.study import cli
from fixture_files import WEBOTS_MOTIONS

FIXTURES = WEBOTS_MOTIONS


def test_defaults_follow_the_paper():
    study = get_study("humanoid-step")
    cfg = resolve_config(study, None, [])
    a = cfg.algorithm
    assert (a.pop_size, a.crossover, a.crossover_params["alpha"]) == (100, "blx_alpha", 0.7)
    assert (a.mutation, a.mutation_rate, a.selection, a.elitism) == (
        "perturb_k", 0.3, "roulette", 0.1)


def test_tiny_run_writes_artifacts(tmp_path):
    study = get_study("humanoid-step")
    cfg = resolve_config(study, None, [
        "algorithm.pop_size=6", "run.generations=2", "run.checkpoint_every=1",
        "problem.intervals=4", "problem.motion_s=0.4", "problem.hold_s=0.2",
        "problem.threads=1"])
    res = run_study(study, cfg, tmp_path, quiet=True)
    assert res.exit_code == 0
    for name in ("best.motion", "fitness.png", "best_replay.json", "stats.csv"):
        assert (tmp_path / name).exists(), name
    assert (tmp_path / "best.mp4").stat().st_size > 1000
    text = (tmp_path / "best.motion").read_text()
    m = read_motion(tmp_path / "best.motion")
    assert m.joints == nao.JOINTS
    assert m.times_ms.tolist() == list(range(0, 401, 40))
    assert format_motion(m) == text  # this project's reader reads it back identically
    problem = study.make_problem(cfg.problem)
    again = genome_motion(problem, res.best_genome)
    np.testing.assert_array_equal(again.values, m.values)
    summary = json.loads((tmp_path / "best_replay.json").read_text())
    assert summary == replay(tmp_path / "best.motion", hold_s=0.2)


def test_videos_off_skips_only_the_video(tmp_path):
    """``run.videos = false``: every artifact but best.mp4, and the log says why; a resume
    may turn videos back on."""
    study = get_study("humanoid-step")
    sets = ["algorithm.pop_size=4", "run.generations=1", "problem.intervals=4",
            "problem.motion_s=0.4", "problem.hold_s=0.2", "problem.threads=1"]
    res = run_study(study, resolve_config(study, None, [*sets, "run.videos=false"]), tmp_path,
                    quiet=True)
    assert res.exit_code == 0
    assert (tmp_path / "best.motion").exists() and (tmp_path / "best_replay.json").exists()
    assert not (tmp_path / "best.mp4").exists()
    assert "best.mp4 skipped: videos are off (run.videos = false)" in \
        (tmp_path / "log.txt").read_text()
    from evomotion.run.resume import resume_config

    _, cfg = resume_config(tmp_path, study, {"run.videos": True, "run.generations": 2})
    assert cfg.run.videos is True
    assert run_study(study, cfg, tmp_path, quiet=True, resume=True).exit_code == 0
    assert (tmp_path / "best.mp4").stat().st_size > 1000


def test_replay_lives_in_one_place():
    """``evomotion replay`` is the only replay command (no study-level copy)."""
    names = {c.name for c in cli.registered_commands}
    assert "replay" not in names and "study" in names


def test_quick_experiment_writes_table(tmp_path):
    from evomotion.studies.humanoid_step.experiment import CROSSOVERS, run_experiment

    lines = []
    results = run_experiment(tmp_path, quick=True, workers=1, echo=lines.append)
    assert {r["crossover"] for r in results} == set(CROSSOVERS)
    for name in ("results.csv", "summary.md", "curves.png"):
        assert (tmp_path / name).exists()
    assert len(list((tmp_path / "curves").glob("*.csv"))) == len(CROSSOVERS)
    table = lines[0]
    for label in CROSSOVERS:
        assert f"| {label} |" in table
    for r in results:
        assert len(r["curve"]) == 3  # generations 0..2
        assert all(row[1] >= row[2] >= row[3] for row in r["curve"])  # max >= mean >= min


def test_default_run_steps_forward_without_falling(tmp_path):
    """The README's main job: defaults only, then replay its best.motion (issues 3 and 13)."""
    import subprocess
    import sys

    out = tmp_path / "run"
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "humanoid-step", "--out",
                        str(out), "--quiet"], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    summary = replay(out / "best.motion", hold_s=2.0)
    assert summary["fell"] is False  # stands through a 2 s hold
    dx, dy = summary["displacement_m"]
    assert dx >= 0.05  # a step: at least 5 cm forward
    assert abs(dy) <= 0.02 and abs(np.degrees(summary["heading_change_rad"])) <= 5.0  # straight
    best = json.loads((out / "best.json").read_text())
    assert best["metrics"]["flight_s"] == 0.0  # no flight phase
    assert (out / "plots" / "fitness.png").exists() and (out / "fitness.png").exists()
    for name in ("best_naoqi.py", "best_keyframes.json", "best_replay.json"):
        assert (out / name).exists()
