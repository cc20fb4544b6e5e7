"""Best-first state-space search with OPEN/CLOSED and re-parenting; A* and weighted A*.

Source: the ordered ("uspořádané") best-first search as given by Ondroušek & Březina
(seed 003, after Mařík 1993), steps 1-7:

1. Put the start state in OPEN; CLOSED is empty.
2. If OPEN is empty there is no solution: stop.
3. Take the state ``i`` with the least ``f(i)`` from OPEN; among ties prefer a goal state,
   otherwise any (here: the one generated first).
4. Move ``i`` from OPEN to CLOSED.
5. If ``i`` is a goal, the solution is found: stop.
6. Expand ``i``; for each successor ``j`` compute ``f(j)``. A ``j`` in neither list goes to
   OPEN. A ``j`` already in OPEN or CLOSED with a larger value gets the new value and the new
   parent and goes (back) to OPEN.
7. Go to 2.

A* (Hart, Nilsson & Raphael 1968) is this algorithm with ``f = g + h``; weighted A*
(Pohl 1970) uses ``f = g + w h``. With an admissible ``h`` and re-opening, A* returns a
least-cost plan; weighted A* one within a factor ``w`` of it.

The search is problem-agnostic: a :class:`SearchProblem` gives the start state, the goal
test, the successors ``(rule, state, step_cost)`` and a hashable duplicate key. Budgets on
expansions and wall time end the search with a stated :attr:`SearchResult.stop_reason`.
"""

from __future__ import annotations

import heapq
import time
from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

FOUND = "found"
OPEN_EMPTY = "open-empty"
EXPANSION_BUDGET = "expansion-budget"
TIME_BUDGET = "time-budget"

# evaluate(parent_f, parent_g, parent_state, child_state, rule, step_cost) -> f(child);
# parent_* are None for the start state.
Evaluate = Callable[[Any, Any, Any, Any, Any, float], float]


class SearchProblem(Protocol):
    """What the search needs to know about a state space."""

    def start(self) -> Any: ...

    def is_goal(self, state: Any) -> bool: ...

    def successors(self, state: Any) -> Sequence[tuple[Any, Any, float]]:
        """``[(rule, child_state, step_cost), ...]`` of the applicable rules."""
        ...

    def key(self, state: Any) -> Hashable:
        """Duplicate-detection key: states with equal keys are the same search node."""
        ...


@dataclass
class SearchResult:
    """Outcome of one search. ``states``/``rules`` are the plan when ``found``."""

    stop_reason: str
    states: list[Any] = field(default_factory=list)
    rules: list[Any] = field(default_factory=list)  # rules[0] is None (the start state)
    cost: float = float("nan")  # sum of the step costs along the plan
    expansions: int = 0
    generated: int = 0
    reopened: int = 0
    seconds: float = 0.0
    # least f on OPEN when the search stopped without a plan (inf if OPEN is empty); for A*
    # with an admissible h a proved lower bound on the least plan cost
    frontier_f: float = float("inf")
    # A* / weighted A* only: a proved lower bound on the least plan cost C* of the searched
    # graph, (cost if found else frontier_f) / weight (see :func:`astar`); nan otherwise
    lower_bound: float = float("nan")

    @property
    def found(self) -> bool:
        return self.stop_reason == FOUND

    @property
    def message(self) -> str:
        """One line saying how the search ended."""
        bound = "" if self.lower_bound != self.lower_bound else \
            f", least cost >= {self.lower_bound:.4g}"
        if self.found:
            return (f"plan found: {len(self.states)} states, cost {self.cost:g}{bound}, "
                    f"{self.expansions} expansions in {self.seconds:.2f} s")
        why = {
            OPEN_EMPTY: "OPEN is empty: the goal is unreachable with these rules",
            EXPANSION_BUDGET: "the expansion budget is spent",
            TIME_BUDGET: "the time budget is spent",
        }[self.stop_reason]
        return (f"no plan: {why} ({self.expansions} expansions in {self.seconds:.2f} s"
                f"{bound})")


def best_first(problem: SearchProblem, evaluate: Evaluate, max_expansions: int = 1_000_000,
               max_seconds: float = float("inf"), min_improvement: float = 1e-9
               ) -> SearchResult:
    """The seed's best-first search (steps 1-7 above) with the evaluation ``evaluate``.

    ``max_expansions`` counts states moved to CLOSED (goal included); 0 expands nothing.
    A known state is re-parented only when its new value is lower by more than
    ``min_improvement``: evaluations that telescope along paths (the seed's (2) and (3))
    would otherwise re-parent on rounding noise and could close a parent cycle.
    """
    t0 = time.perf_counter()
    key_of, successors, is_goal = problem.key, problem.successors, problem.is_goal
    s0 = problem.start()
    k0 = key_of(s0)
    f0 = evaluate(None, None, None, s0, None, 0.0)
    # node record: [f, g, state, parent_key, rule, closed, step_cost]
    nodes: dict[Hashable, list] = {k0: [f0, 0.0, s0, None, None, False, 0.0]}
    heap: list[tuple[float, int, int, Hashable]] = [(f0, 0 if is_goal(s0) else 1, 0, k0)]
    push, pop = heapq.heappush, heapq.heappop
    counter = expansions = generated = reopened = 0
    reason = OPEN_EMPTY
    goal_key = None
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
            reason, goal_key = FOUND, k
            break
        for rule, child, step_cost in successors(state):
            generated += 1
            fc = evaluate(f, g, state, child, rule, step_cost)
            kc = key_of(child)
            old = nodes.get(kc)
            if old is None:
                nodes[kc] = [fc, g + step_cost, child, k, rule, False, step_cost]
            elif fc < old[0] - min_improvement and not is_ancestor(nodes, kc, k):
                if old[5]:
                    reopened += 1
                old[:] = fc, g + step_cost, child, k, rule, False, step_cost
            else:
                continue
            counter += 1
            push(heap, (fc, 0 if is_goal(child) else 1, counter, kc))
    result = SearchResult(reason, expansions=expansions, generated=generated, reopened=reopened)
    if goal_key is not None:
        trace_plan(nodes, goal_key, result)
    else:
        result.frontier_f = frontier_min(nodes, heap)
    result.seconds = time.perf_counter() - t0
    return result


def frontier_min(nodes: dict[Hashable, list], heap: list[tuple]) -> float:
    """The least f of the live (not stale) OPEN entries; inf when there are none."""
    live = [e[0] for e in heap if not nodes[e[-1]][5] and nodes[e[-1]][0] == e[0]]
    return min(live, default=float("inf"))


def is_ancestor(nodes: dict[Hashable, list], candidate: Hashable, k: Hashable) -> bool:
    """Whether ``candidate`` is ``k`` or one of its ancestors (re-parenting there would close a
    cycle: with a duplicate grid, a descendant can map to its ancestor's key)."""
    while k is not None:
        if k == candidate:
            return True
        k = nodes[k][3]
    return False


def trace_plan(nodes: dict[Hashable, list], goal_key: Hashable, result: SearchResult) -> None:
    """Fill ``result.states``/``rules``/``cost`` from the node records (``[f, g, state,
    parent_key, rule, closed, step_cost]``) by following parents back from ``goal_key``."""
    states, rules = [], []
    cost = 0.0
    k = goal_key
    seen = set()
    while k is not None:
        if k in seen:  # a re-parenting cycle would be a bug in the evaluation
            raise RuntimeError("search tree has a parent cycle")
        seen.add(k)
        rec = nodes[k]
        states.append(rec[2])
        rules.append(rec[4])
        cost += rec[6]
        k = rec[3]
    result.states, result.rules = states[::-1], rules[::-1]
    # the traced path's own cost (a stored g can be stale below a re-parented node when f
    # does not depend on g, as with the seed's evaluation (1))
    result.cost = cost


def astar(problem: SearchProblem, heuristic: Callable[[Any], float], weight: float = 1.0,
          max_expansions: int = 1_000_000, max_seconds: float = float("inf")) -> SearchResult:
    """A* (``weight`` = 1) or weighted A* (``f = g + weight * h``) over ``problem``.

    ``heuristic(state)`` must be admissible (never above the least remaining cost) for A*
    to return a least-cost plan; re-opening of CLOSED states keeps this true when it is
    admissible but not consistent.

    ``lower_bound`` of the result: a cost that no plan can beat. While OPEN holds a node
    n of a least-cost plan with its least g (re-opening keeps one there), C* >= g(n) + h(n)
    >= (g(n) + weight h(n)) / weight >= min f on OPEN / weight; a found plan was that
    minimum (h = 0 at the goal), so C* >= cost / weight, i.e. cost <= weight C*.
    """
    return with_lower_bound(best_first(problem, astar_evaluation(heuristic, weight),
                                       max_expansions, max_seconds), weight)


def with_lower_bound(result: SearchResult, weight: float) -> SearchResult:
    """Set ``result.lower_bound`` of an A* search with ``weight`` (see :func:`astar`)."""
    if result.found:
        result.lower_bound = result.cost / weight
    elif result.stop_reason != OPEN_EMPTY:
        result.lower_bound = result.frontier_f / weight
    return result


def astar_evaluation(heuristic: Callable[[Any], float], weight: float = 1.0) -> Evaluate:
    """The evaluation ``f = g + weight * h`` of (weighted) A* for :func:`best_first`."""
    if weight < 1.0:
        raise ValueError(f"weighted A* needs weight >= 1, got {weight}")

    def evaluate(pf: Any, pg: Any, ps: Any, child: Any, rule: Any, step_cost: float) -> float:
        g = 0.0 if pg is None else pg + step_cost
        return g + weight * heuristic(child)

    return evaluate
