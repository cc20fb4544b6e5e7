"""The schedule, the run folder, exit codes and the CLI."""

from __future__ import annotations

import csv
import json
from types import SimpleNamespace

import numpy as np
from typer.testing import CliRunner

from evomotion.studies.arm_ik.driver import EXIT_UNSOLVED, run_schedule
from evomotion.studies.arm_ik.problem import ArmIKConfig, ArmIKProblem
from evomotion.studies.arm_ik.schedule import STATS_COLUMNS, evolve
from evomotion.studies.arm_ik.study import STUDY, cli, run

FAST = dict(pop_size=60, wall_seconds=20.0)


def test_problem_protocol_deterministic_and_batch_independent():
    p = ArmIKProblem(ArmIKConfig(scenario="three_fingers", distance="obstacle"))
    x = p.genome.sample(np.random.default_rng(0), 7)
    e1, e2 = p.evaluate(x), p.evaluate(x[3:4])
    np.testing.assert_array_equal(e1.fitness[3:4], e2.fitness)
    assert set(e1.metrics) == set(p.metric_names)


def test_schedule_solves_seed_example_and_is_reproducible():
    cfg = ArmIKConfig(scenario="seed_example", pictures=False, **FAST)
    r1, r2 = evolve(cfg, 5), evolve(cfg, 5)
    assert r1.solved and r1.best_assessment.intersections[0] == 0
    assert r1.best_assessment.tip_error.max() <= 1e-3 * np.hypot(10, 5)
    np.testing.assert_array_equal(r1.best, r2.best)
    assert [s["phase"] for s in r1.stats[:1]] == ["arm"]
    phases = {s["phase"] for s in r1.stats}
    assert {"arm", "fingers"} <= phases


def test_run_folder_and_best_json(tmp_path):
    cfg = ArmIKConfig(scenario="seed_example", gif_frames=4, **FAST)
    assert run_schedule(cfg, 1, tmp_path) == 0
    for f in ("config.toml", "stats.csv", "best.json", "board.png", "best.gif", "log.txt"):
        assert (tmp_path / f).stat().st_size > 0
    best = json.loads((tmp_path / "best.json").read_text())
    assert list(best)[:7] == ["arm_deg", "fingers_deg", "assignment", "tips", "error",
                              "intersections", "solved"]
    assert best["solved"] is True and len(best["arm_deg"]) == 2
    assert [len(f) for f in best["fingers_deg"]] == [2, 2]
    assert sorted(best["assignment"]) == [0, 1]
    rows = list(csv.DictReader((tmp_path / "stats.csv").read_text().splitlines()))
    assert tuple(rows[0]) == STATS_COLUMNS and rows[-1]["solved"] == "1"
    assert all(0 < float(r["originality"]) <= 1 for r in rows)


def test_unreachable_ends_with_no_solution_and_exit_code(tmp_path, capsys):
    cfg = ArmIKConfig(scenario="unreachable", pictures=False, whole_generations=60,
                      arm_generations=5, finger_generations=5, pop_size=40, wall_seconds=20)
    assert run_schedule(cfg, 0, tmp_path) == EXIT_UNSOLVED == 3
    out = capsys.readouterr().out
    assert "no solution found" in out and "best error" in out
    assert json.loads((tmp_path / "best.json").read_text())["solved"] is False


def test_study_run_adapter(tmp_path):
    cfg = SimpleNamespace(problem=ArmIKConfig(scenario="seed_example", pictures=False, **FAST),
                          run=SimpleNamespace(seed=2, wall_seconds=0.0))
    assert STUDY.run is run and STUDY.name == "arm-ik"
    assert run(cfg, tmp_path, "serial", True) == 0
    assert (tmp_path / "best.json").exists()


def test_cli_check(tmp_path):
    r = CliRunner().invoke(cli, ["check", "corridor"])
    assert r.exit_code == 0 and "3 bones" in r.output
    bad = tmp_path / "bad.scen"
    bad.write_text("10\n5\n5 4\n")
    r = CliRunner().invoke(cli, ["check", str(bad)])
    assert r.exit_code != 0
    assert "number of targets, got end of file" in str(r.exception)


def test_cli_study_table():
    r = CliRunner().invoke(cli, ["study", "--seeds", "1", "--scenario", "seed_example",
                                 "--matching", "optimal"])
    assert r.exit_code == 0, r.output
    assert "| seed_example | optimal | 1/1 (100%) |" in r.output


def test_unreachable_respects_wall_seconds(tmp_path):
    import time

    cfg = ArmIKConfig(scenario="unreachable", pictures=False, whole_generations=10**9,
                      wall_seconds=0.5)
    t = time.perf_counter()
    assert run_schedule(cfg, 1, tmp_path) == EXIT_UNSOLVED
    assert time.perf_counter() - t < 10
