"""The seed's best-first search (steps 1-7) specialised to the walking problem, for speed.

Source: Ondroušek & Březina (seed 003), the ordered best-first search with OPEN/CLOSED and
re-parenting as implemented generically in :func:`evomotion.core.search.best_first`. This
module runs the same algorithm, step for step and in the same order (same successors, same
evaluation values, same tie-breaking counter), so it expands the same states and returns
the same plans; ``tests/studies/quadruped_plan/test_walk_search.py`` checks this against the
generic search. What it saves is the per-successor work on duplicates: about 9 in 10
successors of set B are leg moves onto an already known state. A leg move's duplicate key is
the parent's packed key plus one integer (``WalkProblem.leg_targets``) and its value is
``f(parent) + delta`` (``leg_delta`` of the seed's functions) or a cheap heuristic update
(``evaluate.leg``), so the child state tuple is built only when it enters OPEN.

An evaluation may carry ``leg_delta`` (a float: f(child) = f(parent) + leg_delta for leg
rules) or ``leg(pf, pg, ps, leg, fx, fy, step_cost)``; with neither, leg children are built
and evaluated like body children.
"""

from __future__ import annotations

import heapq
import time
from typing import Any

from evomotion.core.search import (
    EXPANSION_BUDGET,
    FOUND,
    OPEN_EMPTY,
    TIME_BUDGET,
    Evaluate,
    SearchResult,
    astar_evaluation,
    frontier_min,
    is_ancestor,
    trace_plan,
    with_lower_bound,
)
from evomotion.studies.quadruped_plan.rules import WalkProblem


class WalkSearch:
    """The search of :func:`walk_best_first` as an object that runs in batches: ``run(n)``
    expands until ``n`` expansions in total (or a goal, an empty OPEN, the deadline); running
    to 1,000 and then to 2,000 expands exactly what one run to 2,000 does. ``nodes``/``heap``
    are the OPEN/CLOSED records (see :mod:`evomotion.core.search`); :mod:`.search_state`
    turns them into arrays for checkpoints."""

    def __init__(self, problem: WalkProblem, evaluate: Evaluate,
                 min_improvement: float = 1e-9) -> None:
        self.problem, self.evaluate, self.min_improvement = problem, evaluate, min_improvement
        s0 = problem.start()
        f0 = evaluate(None, None, None, s0, None, 0.0)
        # node record: [f, g, state, parent_key, rule, closed, step_cost] (as in core.search)
        self.nodes: dict[int, list] = {s0[11]: [f0, 0.0, s0, None, None, False, 0.0]}
        self.heap: list[tuple[float, int, int, int]] = [(f0, 0 if problem.is_goal(s0) else 1,
                                                         0, s0[11])]
        self.counter = self.expansions = self.generated = self.reopened = 0
        self.reason: str | None = None  # FOUND / OPEN_EMPTY once the search has ended
        self.goal_key: int | None = None
        self.last_f = f0  # f of the last state taken from OPEN
        self.seconds = 0.0
        # ARA* (:mod:`.anytime`): improved closed nodes go here instead of being re-opened
        self.incons: set[int] | None = None
        # ties of f broken towards the deeper state (larger g) instead of the older one: the
        # plan-length heuristic is integer-valued, so weighted A* meets long plateaus of f
        self.deep_ties = False

    def run(self, max_expansions: int, max_seconds: float = float("inf")) -> str:
        """Expand until ``max_expansions`` in total; returns the stop reason of this batch."""
        if self.reason is not None:
            return self.reason
        t0 = time.perf_counter()
        problem, evaluate, min_improvement = self.problem, self.evaluate, self.min_improvement
        nodes, heap = self.nodes, self.heap
        is_goal, body_moves = problem.is_goal, problem.body_moves
        leg_delta = getattr(evaluate, "leg_delta", None)
        leg_eval = getattr(evaluate, "leg", None)
        leg_options, parts = problem.leg_options, problem.parts
        get = nodes.get
        push, pop = heapq.heappush, heapq.heappop
        counter, expansions = self.counter, self.expansions
        generated, reopened = self.generated, self.reopened
        incons, deep = self.incons, self.deep_ties
        goal_flag = -float("inf") if deep else 0  # goals first among equal f
        reason = OPEN_EMPTY
        f = self.last_f
        try:
            while heap:
                if expansions >= max_expansions:
                    reason = EXPANSION_BUDGET
                    break
                if (expansions & 255) == 0 and time.perf_counter() - t0 > max_seconds:
                    reason = TIME_BUDGET
                    break
                f, _, _, k = pop(heap)
                rec = nodes[k]
                if rec[5] or rec[0] != f:  # stale heap entry
                    continue
                rec[5] = True
                expansions += 1
                state, g = rec[2], rec[1]
                if is_goal(state):
                    reason, self.goal_key = FOUND, k
                    break
                for rule, child, step_cost in body_moves(state):
                    generated += 1
                    fc = evaluate(f, g, state, child, rule, step_cost)
                    kc = child[11]
                    old = get(kc)
                    if old is None:
                        nodes[kc] = [fc, g + step_cost, child, k, rule, False, step_cost]
                    elif fc < old[0] - min_improvement and not is_ancestor(nodes, kc, k):
                        if old[5]:
                            if incons is not None:  # ARA*: no re-expansion this iteration
                                old[:] = fc, g + step_cost, child, k, rule, True, step_cost
                                incons.add(kc)
                                continue
                            reopened += 1
                        old[:] = fc, g + step_cost, child, k, rule, False, step_cost
                    else:
                        continue
                    counter += 1
                    push(heap, (fc, goal_flag if is_goal(child) else
                                (-g - step_cost if deep else 1), counter, kc))
                # leg moves keep the body: never a goal here (the parent was not one); cost 1.
                # The same children, in the same order, as problem.leg_targets(state), unrolled.
                opts = leg_options(state)
                if not opts:
                    continue
                key, gc = state[11], g + 1.0
                fl = None if leg_delta is None else f + leg_delta  # f of every leg child
                for part in parts:
                    for leg, moves in opts:
                        generated += len(moves[part])
                        for rule, fx, fy, dk in moves[part]:
                            kc = key + dk
                            if fl is not None:
                                fc = fl
                            elif leg_eval is not None:
                                fc = leg_eval(f, g, state, leg, fx, fy, 1.0)
                            else:
                                fc = evaluate(f, g, state, _child(state, leg, fx, fy, kc), rule,
                                              1.0)
                            old = get(kc)
                            if old is None:
                                nodes[kc] = [fc, gc, _child(state, leg, fx, fy, kc), k, rule,
                                             False, 1.0]
                            elif fc < old[0] - min_improvement and \
                                    not is_ancestor(nodes, kc, k):
                                if old[5]:
                                    if incons is not None:
                                        old[:] = fc, gc, _child(state, leg, fx, fy, kc), k, \
                                            rule, True, 1.0
                                        incons.add(kc)
                                        continue
                                    reopened += 1
                                old[:] = fc, gc, _child(state, leg, fx, fy, kc), k, rule, False, 1.0
                            else:
                                continue
                            counter += 1
                            push(heap, (fc, -gc if deep else 1, counter, kc))
        finally:
            self.counter, self.expansions = counter, expansions
            self.generated, self.reopened, self.last_f = generated, reopened, f
            self.seconds += time.perf_counter() - t0
        if reason in (FOUND, OPEN_EMPTY):
            self.reason = reason
        return reason

    def result(self, reason: str | None = None) -> SearchResult:
        """The :class:`SearchResult` so far (plan traced when found)."""
        result = SearchResult(self.reason or reason or EXPANSION_BUDGET,
                              expansions=self.expansions, generated=self.generated,
                              reopened=self.reopened)
        if self.goal_key is not None:
            trace_plan(self.nodes, self.goal_key, result)
        else:
            result.frontier_f = frontier_min(self.nodes, self.heap)
        result.seconds = self.seconds
        return result


def walk_best_first(problem: WalkProblem, evaluate: Evaluate, max_expansions: int = 1_000_000,
                    max_seconds: float = float("inf"), min_improvement: float = 1e-9
                    ) -> SearchResult:
    """:func:`evomotion.core.search.best_first` on a :class:`WalkProblem` (same results)."""
    search = WalkSearch(problem, evaluate, min_improvement)
    reason = search.run(max_expansions, max_seconds)
    return search.result(reason)


def astar_evaluate(heuristic: Any, weight: float = 1.0) -> Evaluate:
    """The (weighted) A* evaluation, with the leg shortcut when ``heuristic.after_leg`` exists:
    ``after_leg(s, leg, fy)`` (h of ``s`` with foot ``leg`` at body y ``fy``) evaluates leg
    children without building them."""
    evaluate = astar_evaluation(heuristic, weight)
    after_leg = getattr(heuristic, "after_leg", None)
    if after_leg is not None:
        def leg(pf: float, pg: float, ps: tuple, leg: int, fx: float, fy: float,
                step_cost: float) -> float:
            return pg + step_cost + weight * after_leg(ps, leg, fy)

        evaluate.leg = leg  # type: ignore[attr-defined]
    return evaluate


def _child(s: tuple, leg: int, fx: float, fy: float, key: int) -> tuple:
    j = 3 + 2 * leg
    return (*s[:j], fx, fy, *s[j + 2:11], key)


def walk_astar(problem: WalkProblem, heuristic: Any, weight: float = 1.0,
               max_expansions: int = 1_000_000, max_seconds: float = float("inf")
               ) -> SearchResult:
    """:func:`evomotion.core.search.astar` on a :class:`WalkProblem` (same results, including
    ``lower_bound``)."""
    return with_lower_bound(walk_best_first(problem, astar_evaluate(heuristic, weight),
                                            max_expansions, max_seconds), weight)
