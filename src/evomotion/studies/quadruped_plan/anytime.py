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

The search itself is :class:`.walk_search.WalkSearch` (the same successors and tie-breaking);
this module only changes eps between iterations.
"""

from __future__ import annotations

import heapq
import math
import time
from dataclasses import dataclass, field
from typing import Any

from evomotion.core.search import FOUND, OPEN_EMPTY, TIME_BUDGET
from evomotion.studies.quadruped_plan.rules import WalkProblem
from evomotion.studies.quadruped_plan.walk_search import WalkSearch, astar_evaluate

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


def _trace(nodes: dict, key: int) -> tuple[list[tuple], list[Any]]:
    states, rules = [], []
    while key is not None:
        rec = nodes[key]
        states.append(rec[2])
        rules.append(rec[4])
        key = rec[3]
    return states[::-1], rules[::-1]


def _partial(search: WalkSearch, quick: WalkSearch | None, w: float
             ) -> tuple[list[tuple], list[Any]]:
    """The best partial plan: with a first search, the path to its state of least evaluation
    other than the start (the seed's function (3): nearest the goal and best aligned, fewest
    leg moves); else the path to ARA*'s state of least h (then least g)."""
    if quick is not None and len(quick.nodes) > 1:
        start = quick.problem.start()[11]
        nodes = quick.nodes
        key = min((k for k in nodes if k != start), key=lambda k: (nodes[k][0], nodes[k][1]))
        return _trace(nodes, key)
    nodes = search.nodes
    key = min(nodes, key=lambda k: ((nodes[k][0] - nodes[k][1]) / w, nodes[k][1]))
    return _trace(nodes, key)


def _lower_bound(search: WalkSearch, weight: float) -> float:
    """min (g + h) over OPEN u INCONS (h = (f - g) / eps of the current iteration)."""
    incons = search.incons or set()
    best = math.inf
    for key, rec in search.nodes.items():
        if not rec[5] or key in incons:
            v = rec[1] + (rec[0] - rec[1]) / weight
            if v < best:
                best = v
    return best


def _reweight(search: WalkSearch, old: float, new: float, goal_key: int | None) -> None:
    """OPEN <- OPEN u INCONS with f = g + new * h; CLOSED <- {} (ARA* Main, lines 7-9)."""
    incons = search.incons or set()
    is_goal = search.problem.is_goal
    heap = []
    counter = search.counter
    for key, rec in search.nodes.items():
        rec[0] = rec[1] + (rec[0] - rec[1]) * (new / old)
        was_open = not rec[5]
        rec[5] = False
        if was_open or key in incons or key == goal_key:
            counter += 1
            heap.append((rec[0], -math.inf if is_goal(rec[2]) else -rec[1], counter, key))
    heapq.heapify(heap)
    search.heap, search.counter = heap, counter
    search.incons = set()
    search.reason, search.goal_key = None, None


def ara_star(problem: WalkProblem, heuristic: Any, max_expansions: int,
             max_seconds: float = math.inf, weights: tuple[float, ...] = WEIGHTS,
             first: Any = None) -> AnytimePlan:
    """ARA* from ``problem.start()`` within ``max_expansions`` and ``max_seconds``.

    ``first``: an evaluation for a quick first plan before ARA* starts (the seed's
    best-first function (3), :func:`.evaluation.seed_evaluation`): its plan is kept when
    ARA* finds no shorter one, with the bound of ARA*'s last finished iteration (inf when
    none finished)."""
    t0 = time.perf_counter()
    plan = AnytimePlan()
    if problem.is_goal(problem.start()):
        return AnytimePlan([problem.start()], [None], True, 0.0, 1.0, 1.0, stop="optimal")
    used = 0
    if first is not None:
        quick = WalkSearch(problem, first)
        share = 1.0
        reason = quick.run(int(max_expansions * share), max_seconds * share)
        plan.timed_out = reason == TIME_BUDGET
        if reason == OPEN_EMPTY:  # every reachable state seen: no plan exists
            plan.states, plan.rules = [problem.start()], [None]
            plan.stop, plan.expansions = OPEN_EMPTY, quick.expansions
            plan.seconds = time.perf_counter() - t0
            return plan
        if reason == FOUND:
            plan.states, plan.rules = _trace(quick.nodes, quick.goal_key)
            plan.cost, plan.complete = float(len(plan.states) - 1), True
        used = quick.expansions
    search = WalkSearch(problem, astar_evaluate(heuristic, weights[0] if weights else 1.0))
    search.incons, search.deep_ties = set(), True
    goal_key = None
    for i, w in enumerate(weights or ()):
        if i:
            search.evaluate = astar_evaluate(heuristic, w)
            _reweight(search, weights[i - 1], w, goal_key)
        left = max_seconds - (time.perf_counter() - t0)
        reason = search.run(max_expansions - used, left)
        if reason != FOUND:
            plan.stop = reason
            plan.timed_out = plan.timed_out or reason == TIME_BUDGET
            break
        goal_key = search.goal_key
        rec = search.nodes[goal_key]
        lb = _lower_bound(search, w)
        bound = 1.0 if lb == math.inf else max(1.0, min(w, rec[1] / lb if lb > 0 else w))
        if rec[1] < plan.cost:
            plan.states, plan.rules = _trace(search.nodes, goal_key)
            plan.cost, plan.weight = rec[1], w
        plan.complete, plan.iterations = True, i + 1
        plan.bound = min(plan.bound, max(1.0, plan.cost / (rec[1] / bound)))
        if plan.bound <= 1.0:
            plan.stop = "optimal"
            break
    else:
        plan.stop = "optimal" if weights else ("found" if plan.complete else "budget")
    if not plan.complete:
        plan.states, plan.rules = _partial(search, quick if first is not None else None,
                                           weights[min(len(weights) - 1, plan.iterations)]
                                           if weights else 1.0)
    plan.expansions, plan.seconds = used + search.expansions, time.perf_counter() - t0
    return plan
