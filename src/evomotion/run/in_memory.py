"""Run one configuration in memory: the run loop without a run folder.

The studies' experiments (many short runs: a table over seeds, crossovers or maps) and
:func:`evomotion.api.run` without ``out_dir`` run here. It is the loop of
:mod:`evomotion.run.runner` with ``out_dir=None``: no files, no console, no checkpoints, the
stats rows kept in :attr:`~evomotion.run.runner.RunResult.rows`; the same seed gives the same
best genome, fitness and rows as a run with a folder.

A caller gives the problem object (built once and reused over many runs), the factory that
builds it (for ``process``, Ray and Dask workers; default: a copy of the given problem) and the
study's own methods (``algorithm.name -> (config dataclass, driver factory)``, as
:attr:`evomotion.studies.base.Study.algorithms`), so that a study's experiment needs nothing of
its study descriptor and the imports of a study package go one way (descriptor -> experiment).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from evomotion.core.problem import Problem
from evomotion.errors import InputError
from evomotion.run.config import Config
from evomotion.run.runner import RunResult, run_study

#: a study's own methods: ``algorithm.name -> (config dataclass, factory(problem, config))``
Algorithms = Mapping[str, tuple[type, Callable[..., Any]]]


class GivenProblem:
    """``make_problem`` of a problem given as an object: the object itself (picklable when the
    problem is, so process, Ray and Dask workers receive a copy)."""

    def __init__(self, problem: Problem) -> None:
        self.problem = problem

    def __call__(self, _cfg: Any) -> Problem:
        return self.problem


@dataclass(frozen=True)
class _InMemoryStudy:
    """What the run loop reads of a study in a run without a folder (no artifact hooks: an
    in-memory run writes nothing)."""

    name: str
    make_problem: Callable[[Any], Problem]
    algorithms: Algorithms = field(default_factory=dict)
    on_checkpoint: None = None
    finalize: None = None
    best_record: None = None


def run_in_memory(config: Config, problem: Problem | None = None, *,
                  make_problem: Callable[[Any], Problem] | None = None,
                  algorithms: Algorithms | None = None,
                  evaluator: Any = None) -> RunResult:
    """Run ``config`` (a resolved :class:`~evomotion.run.config.Config`; ``config.study`` names
    the run) through the run loop without a folder and return its
    :class:`~evomotion.run.runner.RunResult` (best genome and fitness, stop reason, the driver
    and its final state, the stats rows).

    ``problem``: the problem to run (default: built by ``make_problem`` from
    ``config.problem``, after the run seed is applied as in a run with a folder);
    ``make_problem``: how workers build it (default: a copy of ``problem``); ``algorithms``:
    the study's own methods; ``evaluator``: evaluates every fitness batch (default: the one
    ``run.evaluator`` names; a given one is the caller's to close, so one pool can serve many
    runs). A Ctrl-C ends the run with ``stop_reason == "interrupted"``."""
    if make_problem is None:
        if problem is None:
            raise InputError("run_in_memory: give the problem or make_problem")
        make_problem = GivenProblem(problem)
    study = _InMemoryStudy(config.study, make_problem, dict(algorithms or {}))
    return run_study(study, config, None, quiet=True, problem=problem, evaluator=evaluator)
