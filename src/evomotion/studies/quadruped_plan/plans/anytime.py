"""Anytime planning: ARA* on the walking problem.

Source: M. Likhachev, G. Gordon, S. Thrun, "ARA*: Anytime A* with provable bounds on
sub-optimality", NIPS 2003. Weighted A* (f = g + eps h) is run with a decreasing inflation
eps; within one iteration a CLOSED state whose g improves is not re-expanded but put on
INCONS; between iterations OPEN <- OPEN u INCONS with the new eps, CLOSED <- {} (Fig. 2 of
the paper, ``ImprovePath`` and ``Main``). After each iteration the plan found is within

    eps' = min(eps, g(goal) / min_{s in OPEN u INCONS} (g(s) + h(s)))          (paper, eq. 2)

of the least plan length, for a consistent heuristic (each rule lowers
:func:`.heuristic.plan_length_heuristic` by at most its cost 1; tested). The search stops on
a budget of expansions and seconds and always returns the best plan found so far with its
bound; with no plan yet, a *partial* plan for the receding-horizon walker (:func:`_partial`).

The search is :class:`evomotion.core.search.AraStar` (ARA* of the core search, with the
walking problem's lazy leg moves, :mod:`.walk_search`); this module adds the paper's quick
first plan, keeps the best plan with its bound and makes partial plans.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

from evomotion.core.search import FOUND, OPEN_EMPTY, TIME_BUDGET, AraStar, BestFirstSearch
from evomotion.core.search import trace_path as _trace_path
from evomotion.studies.quadruped_plan.plans.walk_search import (
    WalkSpace,
    astar_evaluate,
    walk_search,
)
from evomotion.studies.quadruped_plan.rules.rules import WalkProblem

WEIGHTS = (3.0, 2.0, 1.5, 1.2, 1.0)  # the inflation schedule eps_0 > ... > 1


@dataclass
class AnytimePlan:
    """A plan (``states``, ``rules``; ``rules[0]`` is None) and what is known about it."""

    states: list[tuple] = field(default_factory=list)
    rules: list[Any] = field(default_factory=list)
    complete: bool = False  # reaches the goal (else a partial plan towards it)
    cost: float = math.inf  # transitions (complete plans)
    bound: float = math.inf  # cost <= bound * least cost (complete plans)
    weight: float = math.inf  # eps of the iteration that found it
    iterations: int = 0  # ARA* iterations finished
    expansions: int = 0
    seconds: float = 0.0
    stop: str = ""  # "optimal", "expansion-budget", "time-budget", "open-empty"
    timed_out: bool = False  # the seconds budget cut a search (results then depend on speed)


def _trace(nodes: dict, key: Any) -> tuple[list[tuple], list[Any]]:
    states, rules, _ = _trace_path(nodes, key)
    return states, rules


def _partial(search: BestFirstSearch, quick: BestFirstSearch | None, w: float
             ) -> tuple[list[tuple], list[Any]]:
    """The best partial plan: with a first search, the path to its state of least evaluation
    other than the start (the seed's function (3): nearest the goal and best aligned, fewest
    leg moves); else the path to ARA*'s state of least h (then least g)."""
    if quick is not None and len(quick.state.nodes) > 1:
        start = quick.problem.start()[11]
        nodes = quick.state.nodes
        key = min((k for k in nodes if k != start), key=lambda k: (nodes[k].f, nodes[k].g))
        return _trace(nodes, key)
    nodes = search.state.nodes
    key = min(nodes, key=lambda k: ((nodes[k].f - nodes[k].g) / w, nodes[k].g))
    return _trace(nodes, key)


def _evaluation_for(heuristic: Any) -> Any:
    def evaluation(w: float) -> tuple:
        ev = astar_evaluate(heuristic, w)
        return ev.evaluate, ev.lazy_evaluate
    return evaluation


def ara_star(problem: WalkProblem, heuristic: Any, max_expansions: int,
             max_seconds: float = math.inf, weights: tuple[float, ...] = WEIGHTS,
             first: Any = None) -> AnytimePlan:
    """ARA* from ``problem.start()`` within ``max_expansions`` and ``max_seconds``.

    ``first``: an evaluation for a quick first plan before ARA* starts (the paper's
    best-first function (3), :func:`.evaluation.paper_evaluation`): its plan is kept when
    ARA* finds no shorter one, with the bound of ARA*'s last finished iteration (inf when
    none finished)."""
    t0 = time.perf_counter()
    if problem.is_goal(problem.start()):
        return AnytimePlan([problem.start()], [None], True, 0.0, 1.0, 1.0, stop="optimal")
    plan, quick = AnytimePlan(), None
    if first is not None:
        quick = walk_search(problem, first)
        if _first_plan(quick, plan, max_expansions, max_seconds):
            plan.seconds = time.perf_counter() - t0
            return plan
    used = 0 if quick is None else quick.state.expansions
    ara = AraStar(WalkSpace(problem), _evaluation_for(heuristic), weights)
    while not ara.done:
        left = max_seconds - (time.perf_counter() - t0)
        it = ara.improve(max_expansions - used, left)
        if it.reason != FOUND:
            plan.stop = it.reason
            plan.timed_out = plan.timed_out or it.reason == TIME_BUDGET
            break
        if it.cost < plan.cost:
            plan.states, plan.rules = _trace(ara.search.state.nodes, it.goal_key)
            plan.cost, plan.weight = it.cost, it.weight
        plan.complete, plan.iterations = True, ara.iteration
        plan.bound = min(plan.bound, max(1.0, plan.cost / (it.cost / it.bound)))
        if plan.bound <= 1.0:
            plan.stop = "optimal"
            break
    else:
        plan.stop = "optimal" if weights else ("found" if plan.complete else "budget")
    if not plan.complete:
        plan.states, plan.rules = _partial(ara.search, quick, weights[min(
            len(weights) - 1, plan.iterations)] if weights else 1.0)
    plan.expansions = used + ara.search.state.expansions
    plan.seconds = time.perf_counter() - t0
    return plan


def _first_plan(quick: BestFirstSearch, plan: AnytimePlan, max_expansions: int,
                max_seconds: float) -> bool:
    """Run the quick first search into ``plan``; True when it proved that no plan exists."""
    reason = quick.run(max_expansions, max_seconds)
    plan.timed_out = reason == TIME_BUDGET
    if reason == OPEN_EMPTY:  # every reachable state seen: no plan exists
        plan.states, plan.rules = [quick.problem.start()], [None]
        plan.stop, plan.expansions = OPEN_EMPTY, quick.state.expansions
        return True
    if reason == FOUND:
        plan.states, plan.rules = _trace(quick.state.nodes, quick.state.goal_key)
        plan.cost, plan.complete = float(len(plan.states) - 1), True
    return False
