"""The study end to end: run folder, make-map, the experiment table, one-line errors."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from evomotion.core.cellular_ga import CGAConfig
from evomotion.core.ga import GAConfig
from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.studies import get_study
from evomotion.studies.grid_path.experiments import (
    algorithm_for,
    beyond_config,
    beyond_table,
    evolve,
    paper_table,
)
from evomotion.studies.grid_path.maps import read_map
from evomotion.studies.grid_path.problem import GridPathConfig, GridPathProblem
from evomotion.studies.grid_path.solvers import all_optima


def cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "evomotion.cli", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=300)


def test_run_folder_and_best_json(tmp_path):
    study = get_study("grid-path")
    cfg = resolve_config(study, overrides=["run.generations=6", "algorithm.pop_size=36",
                                           "algorithm.crossover_rate=0.9",
                                           "algorithm.mutation_rate=0.3"], preset="paper")
    assert isinstance(cfg.algorithm, CGAConfig) and cfg.algorithm.update == "line_sweep"
    assert run_study(study, cfg, tmp_path, quiet=True).exit_code == 0
    best = json.loads((tmp_path / "best.json").read_text())
    assert list(best)[:10] == ["study", "sense", "fitness", "genome", "metrics", "waypoints",
                               "length", "valid", "optima", "gap_percent"]
    assert set(best["optima"]) == set(best["gap_percent"]) == {"octile", "centres", "free"}
    pts = np.array(best["waypoints"])
    assert np.allclose(pts[0], [0.5, 0.5]) and np.allclose(pts[-1], [9.5, 9.5])
    assert best["length"] == pytest.approx(np.hypot(*np.diff(pts, axis=0).T).sum())
    for k, opt in best["optima"].items():
        assert best["gap_percent"][k] == pytest.approx(100 * (best["length"] / opt - 1))
    rows = (tmp_path / "stats.csv").read_text().splitlines()
    assert len(rows) == 1 + 7 and rows[0].startswith("generation,")
    for f in ("path.png", "plots/fitness.png", "config.toml", "log.txt"):
        assert (tmp_path / f).stat().st_size > 0


def test_cga_and_ga_improve_from_valid_paths():
    p = GridPathProblem(GridPathConfig(map="seed15", m=1.1))
    for alg in (algorithm_for("cga-L5-line", 64, 0.9, 0.3), algorithm_for("ga", 64, 0.9, 0.3)):
        r = evolve(p, alg, 0, 15)
        assert r.valid and r.rows[-1]["best_so_far"] < r.rows[0]["best_so_far"]
        assert r.length == pytest.approx(r.fitness)
        assert [row["generation"] for row in r.rows] == list(range(16))
    assert isinstance(algorithm_for("ga", 10, 0.1, 0.1), GAConfig)


def test_repair_reaches_free_optimum_on_easy_map():
    cfg = GridPathConfig(map="seed10a", mode="continuous", n_parts=14, repair=True)
    p = GridPathProblem(cfg)
    r = evolve(p, CGAConfig(pop_size=36, update="synchronous", crossover_rate=0.9,
                            mutation_rate=0.3), 0, 20)
    free = all_optima(p.map)["free"].length
    assert r.valid and r.length <= 1.01 * free


def test_tiny_tables():
    rows = list(paper_table(1, ["seed10a"], ["cga-L5-line", "ga"], 0.9, 0.3, generations=3))
    assert [r.config for r in rows] == ["cga-L5-line", "ga"]
    assert all(0 <= r.success <= 1 and r.mean_length >= r.best_length for r in rows)
    assert "| seed10a | ga |" in rows[1].line()
    b = list(beyond_table(1, 1, ["paper-encoding"], 16, 2, 0.9, 0.3, update="sync"))
    assert b[0].config == "paper-encoding"
    # "seed-encoding" is the old name of the row (benchmarks and old commands use it)
    assert beyond_config("seed-encoding", "seed10a") == beyond_config("paper-encoding", "seed10a")


def test_cli_make_map_and_study(tmp_path):
    r = cli("grid-path", "make-map", "--size", "12", "--density", "0.3", "--seed", "3",
            "m.map", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    m = read_map(tmp_path / "m.map")
    assert m.width == 12 and m.blocked.sum() == round(0.3 * 144)
    r = cli("grid-path", "study", "--experiment", "seed", "--seeds", "1", "--map", "seed10a",
            "--row", "cga-L5-sync", "--generations", "2", cwd=tmp_path)
    assert r.returncode == 0, r.stderr  # "seed": the old name of the paper experiment
    assert "note: --experiment seed is the old name of --experiment paper" in r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].startswith("rows: --preset paper") and "literal rates" in lines[0]
    assert lines[1].startswith("| map |") and "cga-L5-sync" in r.stdout


@pytest.mark.parametrize(("args", "msg"), [
    (["run", "grid-path", "--set", "problem.map=nope"], "neither a file nor a bundled map"),
    (["run", "grid-path", "--set", "problem.start=8,1"], "start cell (8, 1) is blocked"),
    (["run", "grid-path", "--set", "algorithm.neighbourhood=hex"], "unknown neighbourhood"),
    (["grid-path", "study", "--map", "x"], "unknown 'x'"),
    (["grid-path", "study", "--experiment", "beyond", "--update", "zig"], "--update: expected"),
    (["grid-path", "study", "--experiment", "other"],
     "--experiment: expected one of paper, beyond"),
    (["run", "grid-path", "--preset", "fast"], "unknown preset 'fast'"),
    (["run", "grid-path", "--set", "algorithm.name='cmaes'"], "available: cga, ga"),
])
def test_bad_input_is_one_line_error(tmp_path, args, msg):
    r = cli(*args, cwd=tmp_path)
    assert r.returncode == 2 and msg in r.stderr and "Traceback" not in r.stderr


def _run_folder(tmp, evaluator: str):
    study = get_study("grid-path")
    cfg = resolve_config(study, overrides=["run.generations=5", "algorithm.pop_size=36",
                                           "algorithm.crossover_rate=0.9",
                                           "algorithm.mutation_rate=0.3", "run.seed=4",
                                           f"run.evaluator='{evaluator}'", "run.workers=2",
                                           "run.chunks_per_worker=2"])
    assert run_study(study, cfg, tmp, quiet=True).exit_code == 0
    stats = [line.split(",") for line in (tmp / "stats.csv").read_text().splitlines()]
    timed = {stats[0].index("wall_s"), stats[0].index("evals_per_s")}
    return (tmp / "best.json").read_text(), [[v for i, v in enumerate(r) if i not in timed]
                                             for r in stats]


def test_process_evaluator_is_bit_identical_to_serial(tmp_path):
    serial = _run_folder(tmp_path / "serial", "serial")
    process = _run_folder(tmp_path / "process", "process")
    assert process == serial


def test_evolve_evaluates_every_batch_through_the_evaluator():
    from evomotion.run.evaluators import SerialEvaluator

    p = GridPathProblem(GridPathConfig(map="seed10a"))
    sizes: list[int] = []

    class Spy(SerialEvaluator):
        def __call__(self, x):
            sizes.append(len(x))
            return super().__call__(x)

    r = evolve(p, algorithm_for("cga-L5-line", 36, 0.9, 0.3), 1, 3,
               evaluator=Spy(lambda _c: p, None))
    assert sum(sizes) == r.evaluations and sizes[0] == 36 and len(sizes) > 4
    assert evolve(p, algorithm_for("cga-L5-line", 36, 0.9, 0.3), 1, 3).genome.tolist() \
        == r.genome.tolist()
