"""The schedule, the run folder, exit codes and the CLI."""

from __future__ import annotations

import csv
import json

import numpy as np
from typer.testing import CliRunner

from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.run.stats import COLUMNS
from evomotion.studies.arm_ik.artifacts import EXIT_UNSOLVED
from evomotion.studies.arm_ik.experiment import evolve
from evomotion.studies.arm_ik.problem import ArmIKConfig, ArmIKProblem
from evomotion.studies.arm_ik.schedule import EXTRA_COLUMNS
from evomotion.studies.arm_ik.study import STUDY, cli


def run_schedule(sets: list[str], seed: int, out) -> int:
    cfg = resolve_config(STUDY, None, [f"run.seed={seed}", *sets])
    return run_study(STUDY, cfg, out, quiet=True).exit_code


def test_problem_protocol_deterministic_and_batch_independent():
    p = ArmIKProblem(ArmIKConfig(scenario="three_fingers", distance="obstacle"))
    x = p.genome.sample(np.random.default_rng(0), 7)
    e1, e2 = p.evaluate(x), p.evaluate(x[3:4])
    np.testing.assert_array_equal(e1.fitness[3:4], e2.fitness)
    assert set(p.metric_names) <= set(e1.metrics)
    a = p.assessment_of(e1)  # the schedule's view of an evaluation from any evaluator
    np.testing.assert_array_equal(a.distance, p.assess(x).distance)


def test_schedule_solves_paper_example_and_is_reproducible():
    cfg = ArmIKConfig(scenario="paper_example", pictures=False)
    r1, r2 = evolve(cfg, 5, wall_seconds=20), evolve(cfg, 5, wall_seconds=20)
    assert r1.solved and r1.best_assessment.intersections[0] == 0
    assert r1.best_assessment.tip_error.max() <= 1e-3 * np.hypot(10, 5)
    np.testing.assert_array_equal(r1.best, r2.best)
    assert r1.generations > 15 and r1.time_to_solution_s > 0


def test_run_folder_and_best_json(tmp_path):
    assert run_schedule(["problem.gif_frames=4"], 1, tmp_path) == 0
    for f in ("config.toml", "stats.csv", "best.json", "board.png", "best.gif", "log.txt"):
        assert (tmp_path / f).stat().st_size > 0
    best = json.loads((tmp_path / "best.json").read_text())
    assert list(best)[:12] == ["study", "sense", "fitness", "genome", "metrics", "arm_deg",
                               "fingers_deg", "assignment", "tips", "error", "intersections",
                               "solved"]
    assert best["solved"] is True and len(best["arm_deg"]) == 2
    assert [len(f) for f in best["fingers_deg"]] == [2, 2]
    assert sorted(best["assignment"]) == [0, 1]
    rows = list(csv.DictReader((tmp_path / "stats.csv").read_text().splitlines()))
    assert tuple(rows[0]) == COLUMNS + EXTRA_COLUMNS and rows[-1]["solved"] == "1"
    assert all(0 < float(r["originality"]) <= 1 for r in rows)
    assert [r["phase"] for r in rows[:2]] == ["init", "arm"]
    assert {"arm", "fingers"} <= {r["phase"] for r in rows}
    log = (tmp_path / "log.txt").read_text()
    assert "arm phase" in log and "fingers phase" in log and "solved paper_example" in log


def test_unreachable_ends_with_no_solution_and_exit_code(tmp_path):
    sets = ["problem.scenario='unreachable'", "problem.pictures=false",
            "algorithm.whole_generations=60", "algorithm.arm_generations=5",
            "algorithm.finger_generations=5", "algorithm.pop_size=40"]
    assert run_schedule(sets, 0, tmp_path) == EXIT_UNSOLVED == 3
    log = (tmp_path / "log.txt").read_text()
    assert "no solution found" in log and "best error" in log
    assert "stopped: whole_generations at generation 70" in log
    assert json.loads((tmp_path / "best.json").read_text())["solved"] is False


def test_ga_settings_are_the_algorithm_section(tmp_path):
    cfg = resolve_config(STUDY, None, ["algorithm.pop_size=50"])
    assert cfg.algorithm.name == "schedule" and cfg.algorithm.pop_size == 50
    import pytest

    from evomotion.errors import InputError

    with pytest.raises(InputError, match="unknown key 'problem.pop_size'"):
        resolve_config(STUDY, None, ["problem.pop_size=50"])
    with pytest.raises(InputError, match="available: schedule"):
        resolve_config(STUDY, None, ["algorithm.name='ga'"])


def test_cli_check(tmp_path):
    r = CliRunner().invoke(cli, ["check", "corridor"])
    assert r.exit_code == 0 and "3 bones" in r.output
    bad = tmp_path / "bad.scen"
    bad.write_text("10\n5\n5 4\n")
    r = CliRunner().invoke(cli, ["check", str(bad)])
    assert r.exit_code != 0
    assert "number of targets, got end of file" in str(r.exception)


def test_cli_study_table():
    r = CliRunner().invoke(cli, ["study", "--seeds", "1", "--scenario", "paper_example",
                                 "--matching", "optimal"])
    assert r.exit_code == 0, r.output
    assert "| paper_example | optimal | 1/1 (100%) |" in r.output


def test_unreachable_respects_wall_seconds(tmp_path):
    import time

    sets = ["problem.scenario='unreachable'", "problem.pictures=false",
            "algorithm.whole_generations=1000000000", "run.wall_seconds=0.5"]
    t = time.perf_counter()
    assert run_schedule(sets, 1, tmp_path) == EXIT_UNSOLVED
    assert time.perf_counter() - t < 10
