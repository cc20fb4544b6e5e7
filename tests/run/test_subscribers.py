"""The run loop's subscribers and declared contracts: events in order, the study's hooks
typed (no look-up by name), and run/ importing nothing of sim/, studies/ or the API."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import numpy as np

import evomotion.run as run_package
from evomotion.run.config import resolve_config
from evomotion.run.contracts import (
    OwnInitialPopulation,
    OwnMutation,
    RunStudy,
    SeededByRun,
    Subscriber,
)
from evomotion.run.runner import run_study

sys.path.insert(0, str(Path(__file__).parent))
from toy_study import STUDY  # noqa: E402


class Recorder(Subscriber):
    """Every event, in order."""

    def __init__(self) -> None:
        self.events: list[tuple[str, int]] = []

    def on_start(self, run) -> None:
        self.events.append(("start", run.counters.generation))

    def on_step(self, run, step) -> None:
        assert step.row["generation"] == run.counters.generation
        self.events.append(("step", run.counters.generation))

    def on_checkpoint(self, run) -> None:
        self.events.append(("checkpoint", run.counters.generation))

    def on_close(self, run) -> None:
        self.events.append(("close", run.counters.generation))

    def on_finish(self, ctx, code: int) -> int:
        assert (ctx.out_dir / "best.json").exists()  # after the run's own artifacts
        self.events.append(("finish", ctx.generation))
        return code


def test_a_subscriber_hears_every_event_in_order(tmp_path):
    cfg = resolve_config(STUDY, None, ["run.generations=6", "run.checkpoint_every=3",
                                       "problem.nan_above=99", "problem.raise_above=99"])
    rec = Recorder()
    res = run_study(STUDY, cfg, tmp_path, quiet=True, subscribers=[rec])
    assert res.exit_code == 0
    assert rec.events == [("start", -1), ("step", 0), ("checkpoint", 0),
                          *[("step", g) for g in range(1, 4)], ("checkpoint", 3),
                          *[("step", g) for g in range(4, 7)], ("close", 6), ("finish", 6)]


def test_a_run_without_a_folder_has_no_finishing_phase():
    cfg = resolve_config(STUDY, None, ["run.generations=2", "problem.nan_above=99",
                                       "problem.raise_above=99"])
    rec = Recorder()
    res = run_study(STUDY, cfg, None, subscribers=[rec])
    assert [e for e, _ in rec.events if e != "checkpoint"] == ["start", "step", "step", "step",
                                                               "close"]  # no "finish"
    assert len(res.rows) == 3


def test_a_study_declares_its_hooks_and_problems_theirs():
    assert isinstance(STUDY, RunStudy)

    class Own:
        def mutate(self, x, rng, rate):
            return x

        def initial_population(self, n, rng):
            return np.zeros((n, 2))

    assert isinstance(Own(), OwnMutation) and isinstance(Own(), OwnInitialPopulation)
    assert not isinstance(STUDY.make_problem(STUDY.problem_config()), OwnMutation)
    assert not isinstance(STUDY.problem_config(), SeededByRun)


def test_run_imports_nothing_above_it():
    """run/ knows nothing of physics, robots or studies (the callable-module shim in
    run/__init__.py, which calls the API, is the one exception)."""
    root = Path(run_package.__file__).parent
    found = []
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            for name in names:
                if name.split(".")[:2] in (["evomotion", "sim"], ["evomotion", "studies"],
                                           ["evomotion", "api"], ["evomotion", "cli"],
                                           ["evomotion", "studio"]):
                    found.append(f"{path.relative_to(root)}: {name}")
    assert found == ["__init__.py: evomotion.api"]
