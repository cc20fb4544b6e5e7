"""ARA*: anytime weighted A* that reuses its search between decreasing inflations.

Source: M. Likhachev, G. Gordon, S. Thrun, "ARA*: Anytime A* with provable bounds on
sub-optimality", NIPS 2003. Weighted A* (f = g + eps h) is run with a decreasing inflation
eps; within one iteration (``ImprovePath``) a CLOSED state whose g improves is not
re-expanded but put on INCONS; between iterations OPEN <- OPEN u INCONS with the new eps,
CLOSED <- {} (Fig. 2 of the paper, ``Main``). After each iteration the plan found is within

    eps' = min(eps, g(goal) / min_{s in OPEN u INCONS} (g(s) + h(s)))          (paper, eq. 2)

of the least cost, for a consistent heuristic. Ties of f go to a goal, then to the deeper
state (:func:`.nodes.goal_first_deeper`): integer-valued heuristics meet long plateaus of f.
The search is :class:`.best_first.BestFirstSearch` with its INCONS set switched on.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable, Hashable
from dataclasses import dataclass, field
from typing import Any

from evomotion.core.search.astar import astar_evaluation
from evomotion.core.search.best_first import BestFirstSearch
from evomotion.core.search.nodes import (
    FOUND,
    Evaluate,
    LazyEvaluate,
    SearchProblem,
    goal_first_deeper,
    trace_path,
)

# evaluation_for(eps) -> (evaluate, lazy_evaluate or None) of f = g + eps h
EvaluationFor = Callable[[float], tuple[Evaluate, LazyEvaluate | None]]


@dataclass(frozen=True)
class AraIteration:
    """One ``ImprovePath``: its inflation, how it ended and, when it found the goal, the
    goal's key, cost g(goal) and the bound eps' of eq. 2."""

    weight: float
    reason: str
    goal_key: Hashable | None = None
    cost: float = math.inf
    bound: float = math.inf


class AraStar:
    """ARA* over ``problem`` with the inflations ``weights`` (eps_0 > ... >= 1), one
    :meth:`improve` per iteration so that the caller keeps its own budget and plans."""

    def __init__(self, problem: SearchProblem, evaluation_for: EvaluationFor,
                 weights: tuple[float, ...], **options: Any) -> None:
        self.weights, self.evaluation_for = tuple(weights), evaluation_for
        evaluate, lazy = evaluation_for(self.weights[0] if self.weights else 1.0)
        self.search = BestFirstSearch(problem, evaluate, lazy_evaluate=lazy,
                                      tie_break=goal_first_deeper, **options)
        self.search.state.incons = set()
        self.iteration = 0  # iterations finished
        self.goal_key: Hashable | None = None

    @property
    def done(self) -> bool:
        return self.iteration >= len(self.weights)

    def improve(self, max_expansions: int, max_seconds: float = math.inf) -> AraIteration:
        """Run the next iteration until the goal is expanded or ``max_expansions`` in total
        (or ``max_seconds`` of this call) are spent."""
        i, search = self.iteration, self.search
        w = self.weights[i]
        if i:
            search.evaluate, search.lazy_evaluate = self.evaluation_for(w)
            reweight(search, self.weights[i - 1], w, self.goal_key)
        reason = search.run(max_expansions, max_seconds)
        if reason != FOUND:
            return AraIteration(w, reason)
        self.goal_key = key = search.state.goal_key
        g = search.state.nodes[key].g
        lb = open_lower_bound(search, w)
        bound = 1.0 if lb == math.inf else max(1.0, min(w, g / lb if lb > 0 else w))
        self.iteration += 1
        return AraIteration(w, FOUND, key, g, bound)


def open_lower_bound(search: BestFirstSearch, weight: float) -> float:
    """min (g + h) over OPEN u INCONS (h = (f - g) / eps of the current iteration)."""
    st = search.state
    incons, closed = st.incons or set(), st.closed
    best = math.inf
    for key, node in st.nodes.items():
        if key not in closed or key in incons:
            v = node.g + (node.f - node.g) / weight
            if v < best:
                best = v
    return best


def reweight(search: BestFirstSearch, old: float, new: float, goal_key: Hashable | None
             ) -> None:
    """OPEN <- OPEN u INCONS with f = g + new * h; CLOSED <- {} (``Main``, lines 7-9). The
    last goal goes back to OPEN too, so the next iteration can end on it at once."""
    st = search.state
    incons, closed, is_goal, tie = st.incons or set(), st.closed, search.problem.is_goal, \
        search.tie_break
    heap = []
    counter = st.counter
    for key, node in st.nodes.items():
        node.f = node.g + (node.f - node.g) * (new / old)
        if key not in closed or key in incons or key == goal_key:
            counter += 1
            heap.append((node.f, tie(is_goal(node.state), node.g, key, node.state), counter,
                         key))
    heapq.heapify(heap)
    st.open, st.counter, st.closed, st.incons = heap, counter, set(), set()
    st.reason, st.goal_key = None, None


@dataclass
class AraResult:
    """The best plan of an :func:`ara_star` run and its iterations."""

    iterations: list[AraIteration] = field(default_factory=list)
    states: list[Any] = field(default_factory=list)
    rules: list[Any] = field(default_factory=list)
    cost: float = math.inf
    bound: float = math.inf  # cost <= bound * least cost
    expansions: int = 0


def ara_star(problem: SearchProblem, heuristic: Callable[[Any], float],
             weights: tuple[float, ...] = (3.0, 2.0, 1.5, 1.2, 1.0),
             max_expansions: int = 1_000_000) -> AraResult:
    """ARA* until the last inflation finishes, the bound reaches 1 or the budget is spent."""
    ara = AraStar(problem, lambda w: (astar_evaluation(heuristic, w), None), weights)
    out = AraResult()
    while not ara.done:
        it = ara.improve(max_expansions)
        out.iterations.append(it)
        if it.reason != FOUND:
            break
        if it.cost < out.cost:
            out.states, out.rules, _ = trace_path(ara.search.state.nodes, it.goal_key)
            out.cost = it.cost
        out.bound = min(out.bound, max(1.0, out.cost / (it.cost / it.bound)))
        if out.bound <= 1.0:
            break
    out.expansions = ara.search.state.expansions
    return out
