"""The crossover experiment runs its cases one after the other through the in-memory run loop
and evaluates through the run loop's evaluators (one ``process`` pool for the whole study, closed
at the end; none of its own): the table does not depend on ``workers``."""

from __future__ import annotations

from evomotion.run.evaluators import SerialEvaluator
from evomotion.studies.humanoid_step import experiment


def test_one_run_loop_evaluator_for_the_study_and_the_same_table(tmp_path, monkeypatch):
    made: list = []

    def make_evaluator(name, make_problem, problem_cfg, workers):
        made.append((name, workers))
        ev = SerialEvaluator(make_problem, problem_cfg)  # in this process: a fast test
        ev.close = lambda: made.append("closed")  # type: ignore[method-assign]
        return ev

    monkeypatch.setattr(experiment, "make_evaluator", make_evaluator)
    tables = []
    for workers in (3, 1):
        out = tmp_path / f"w{workers}"
        out.mkdir()
        experiment.run_experiment(out, quick=True, workers=workers, echo=lambda _s: None)
        tables.append([(out / n).read_text() for n in ("results.csv", "summary.md")]
                      + [p.read_text() for p in sorted((out / "curves").iterdir())])
    assert made == [("process", 3), "closed"]  # workers = 1: this process, no pool
    assert tables[0] == tables[1]
