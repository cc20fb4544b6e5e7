"""The step loop: one driver step at a time, each announced to the run's subscribers.

A step advances the driver, updates the :class:`~evomotion.run.counters.Counters`, builds the
``stats.csv`` row and applies the stop rules (:mod:`evomotion.run.stopping`); then every
subscriber sees it (``on_step``), and, when a periodic checkpoint is due, ``on_checkpoint``.
The loop itself writes nothing but the run log's lines about failed individuals; the
subscribers (:mod:`evomotion.run.recorders`, :mod:`evomotion.run.artifacts`) hold the files,
as EvoTorch's searcher hooks do (Toklu et al. 2023, arXiv:2302.12600).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from evomotion.run.context import RunContext
from evomotion.run.contracts import Subscriber
from evomotion.run.run_state import RunState, StepRecord
from evomotion.run.stats import diversity, population_stats
from evomotion.run.stopping import stop_reason


def step_once(run: RunState, evaluator: Any, t_start: float) -> StepRecord:
    """One step of the driver (``t_start``: the run's start on the clock, earlier sessions
    included), its row and stop reason."""
    c, log, driver, sgn = run.counters, run.log, run.driver, run.sgn
    t0 = time.perf_counter()
    run.state, rep = driver.step(run.state, run.rng, evaluator)
    c.evaluations += rep.evaluations
    c.generation += 1
    if rep.failed:
        c.failed_total += rep.failed
        first = rep.errors[0] if rep.errors else "non-finite fitness"
        log(f"generation {c.generation}: {rep.failed} individual(s) failed and got the worst "
            f"fitness ({first})")
    for line in rep.lines:
        log(f"generation {c.generation}: {line}")
    if rep.best_metrics is not None:
        c.best_metrics = rep.best_metrics
    _, best_cost = driver.best(run.state)
    ps = population_stats(sgn * np.asarray(rep.cost, float))
    dt = time.perf_counter() - t0
    c.wall_s = time.perf_counter() - t_start
    best_now = ps["max"] if driver.sense == "max" else ps["min"]
    div = diversity(rep.population, run.problem.genome.span) \
        if rep.population is not None else float("nan")
    row = {"generation": c.generation, "evaluations": c.evaluations, "best": best_now, **ps,
           "best_so_far": sgn * best_cost, "wall_s": round(c.wall_s, 4),
           "evals_per_s": round(rep.evaluations / dt, 2) if dt > 0 else float("nan"),
           "diversity": div, "failed": rep.failed, **rep.extras}
    reason = stop_reason(driver, run.state, run.config, c, best_cost, ps["mean"] * sgn, sgn)
    c.stop_reason, c.reason_recorded = reason, True
    every = run.config.run.checkpoint_every
    due = bool(reason is None and every and c.generation % every == 0)
    return StepRecord(rep, row, reason, due)


def run_steps(run: RunState, subscribers: Sequence[Subscriber], evaluator: Any) -> str:
    """Step until a stop rule fires; the stop reason (a resumed run that only writes its
    final artifacts has its reason already, and takes no step). Ctrl-C and errors propagate
    (the caller closes the subscribers: :func:`close`)."""
    reason = run.counters.stop_reason
    t_start = time.perf_counter() - run.counters.wall_s
    while reason is None:
        step = step_once(run, evaluator, t_start)
        for sub in subscribers:
            sub.on_step(run, step)
        if step.due:
            for sub in subscribers:
                sub.on_checkpoint(run)
        reason = step.reason
    return reason


def start(run: RunState, subscribers: Sequence[Subscriber]) -> None:
    """``on_start`` of every subscriber: the loop is about to begin."""
    for sub in subscribers:
        sub.on_start(run)


def close(run: RunState, subscribers: Sequence[Subscriber]) -> None:
    """``on_close`` of every subscriber: the loop has ended, however it ended."""
    for sub in subscribers:
        sub.on_close(run)


def finish(subscribers: Sequence[Subscriber], ctx: RunContext, code: int) -> int:
    """The finishing phase: ``on_finish`` of every subscriber in order; the exit code."""
    for sub in subscribers:
        code = sub.on_finish(ctx, code)
    return code
