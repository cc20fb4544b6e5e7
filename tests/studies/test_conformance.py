"""One conformance check over every registered study, with no exemptions.

For each study, with a tiny config: it resolves, runs through the one run loop, writes the
engine's files (stats.csv with the core columns first, best.json with the envelope, a fitness
plot), and a run interrupted by Ctrl-C or killed with SIGKILL resumes to the same results as an
uninterrupted one, bit for bit.
"""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from evomotion.run import runner
from evomotion.run.config import resolve_config, study_algorithms
from evomotion.run.contracts import ContextRows
from evomotion.run.faults import fault_at
from evomotion.run.runner import EXIT_INTERRUPTED, run_study
from evomotion.run.stats import COLUMNS, read_stats
from evomotion.studies import STUDIES, get_study

STEPS = 6  # generations 0..5
CUT = 3  # the interrupted runs stop during this step (the last checkpoint is at 2)
TIMED = {"wall_s", "evals_per_s"}


def _overrides(name: str) -> list[str]:
    return [*get_study(name).smoke, f"run.generations={STEPS - 1}", "run.checkpoint_every=2",
            "run.wall_seconds=0", "run.seed=3", "run.videos=false"]


def _same(d1: Path, d2: Path) -> None:
    s1, s2 = read_stats(d1 / "stats.csv"), read_stats(d2 / "stats.csv")
    assert list(s1) == list(s2)
    for col in s1:
        if col not in TIMED:
            np.testing.assert_array_equal(s1[col], s2[col], err_msg=col)
    b1, b2 = (json.loads((d / "best.json").read_text()) for d in (d1, d2))
    for k in b1:
        if k not in ("time_to_solution_s",):
            assert b1[k] == b2[k], k


def test_every_study_has_a_smoke_config():
    assert all(get_study(n).smoke for n in STUDIES)


@pytest.fixture(params=sorted(STUDIES))
def name(request):
    return request.param


def test_descriptor(name):
    s = get_study(name)
    assert s.name == name and s.description and len(s.description.splitlines()) == 1
    assert dataclasses.is_dataclass(s.problem_config)
    assert s.problem_config.__dataclass_params__.frozen
    cfg = resolve_config(s)  # the study's defaults resolve against the typed config
    assert cfg.algorithm.name in study_algorithms(s)
    for preset in s.presets:
        resolve_config(s, preset=preset)
        assert s.preset_notes.get(preset)
    from evomotion.sim.robots import bundled_robots

    for alg, keys in s.algorithm_tunings.items():  # a method of the study; every key applies
        cfg = resolve_config(s, overrides=[f"algorithm.name={alg!r}"])
        assert {k: getattr(cfg.algorithm, k) for k in keys} == dict(keys, name=alg), alg
    assert isinstance(s.defaults_key, str)
    assert not s.robot_defaults or \
        s.defaults_key in {f.name for f in dataclasses.fields(s.problem_config)}
    keyed = [(None, r, sections) for r, sections in s.robot_defaults.items()]
    for preset, by_robot in s.robot_presets.items():  # a preset's setting on a robot
        assert preset in s.presets, preset
        keyed += [(preset, r, sections) for r, sections in by_robot.items()]
    for preset, robot, sections in keyed:  # a bundled robot; every key applies
        if s.defaults_key == "robot":  # "": the study's own robot
            assert robot in bundled_robots() or robot == ""
        cfg = resolve_config(s, preset=preset,
                             overrides=[f"problem.{s.defaults_key}={robot!r}"] * bool(robot))
        for section, values in sections.items():
            for key, value in values.items():
                got = getattr(getattr(cfg, section), key)
                assert (list(got) if isinstance(got, tuple) else got) == value, \
                    (preset, robot, section, key)


def test_run_interrupt_and_resume_are_bit_identical(name, tmp_path):
    s = get_study(name)
    cfg = resolve_config(s, None, _overrides(name))
    full = run_study(s, cfg, tmp_path / "full", quiet=True)
    assert full.generation >= CUT + 1, "the smoke config must run past the cut"
    stats = (tmp_path / "full" / "stats.csv").read_text().splitlines()
    assert tuple(stats[0].split(","))[:len(COLUMNS)] == COLUMNS
    best = json.loads((tmp_path / "full" / "best.json").read_text())
    assert list(best)[:5] == ["study", "sense", "fitness", "genome", "metrics"]
    assert best["study"] == name and best["sense"] in ("min", "max")
    assert (tmp_path / "full" / "plots" / "fitness.png").stat().st_size > 0

    with fault_at(CUT, "interrupt"):
        cut_res = run_study(s, cfg, tmp_path / "cut", quiet=True)
    assert cut_res.stop_reason == "interrupted" and cut_res.exit_code == EXIT_INTERRUPTED
    run_study(s, cfg, tmp_path / "cut", quiet=True, resume=True)
    _same(tmp_path / "full", tmp_path / "cut")


KILLER = textwrap.dedent("""
    import sys
    from evomotion.run.config import resolve_config
    from evomotion.run.faults import fault_at
    from evomotion.run.runner import run_study
    from evomotion.studies import get_study
    name, out, cut = sys.argv[1], sys.argv[2], int(sys.argv[3])
    s = get_study(name)
    with fault_at(cut, "sigkill"):
        run_study(s, resolve_config(s, None, sys.argv[4:]), out, quiet=True)
""")


def test_kill_9_then_resume_is_bit_identical(name, tmp_path):
    s = get_study(name)
    cfg = resolve_config(s, None, _overrides(name))
    run_study(s, cfg, tmp_path / "full", quiet=True)
    out = tmp_path / "killed"
    out.mkdir()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    r = subprocess.run([sys.executable, "-c", KILLER, name, str(out), str(CUT),
                        *_overrides(name)], env=env, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == -9, r.stderr
    assert len((out / "stats.csv").read_text().splitlines()) == 1 + CUT  # rows 0..CUT-1
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "resume", str(out), "-q"],
                       env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode in (0, 1, 3), r.stderr  # a study's own "not solved" codes
    assert "Traceback" not in r.stderr
    _same(tmp_path / "full", out)
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "plot", str(out)], env=env,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and "fitness.png" in r.stdout, r.stderr


def test_batch_evaluation_is_deterministic_and_composable(name):
    """Where there is batch evaluation, an individual's result depends on it alone (what
    makes every evaluator bit-identical)."""
    s = get_study(name)
    cfg = resolve_config(s, None, list(s.smoke))
    problem = s.make_problem(cfg.problem)
    if not runner.build_driver(s, cfg, problem).uses_evaluator:
        assert cfg.run.evaluator == "serial"
        return
    g = problem.genome
    assert g.lower.shape == g.upper.shape == (g.dim,) and np.all(g.lower <= g.upper)
    assert problem.sense in ("min", "max")
    x = g.sample(np.random.default_rng(0), 2)
    if isinstance(problem, ContextRows):  # rows = genome + context (a policy's normaliser)
        x = problem.evaluation_rows(x)
    ev1, ev2 = problem.evaluate(x), problem.evaluate(x)
    assert ev1.fitness.shape == (2,)
    assert set(ev1.metrics) >= set(problem.metric_names)
    np.testing.assert_array_equal(ev1.fitness, ev2.fitness)
    np.testing.assert_array_equal(problem.evaluate(x[1:2]).fitness, ev1.fitness[1:2])
