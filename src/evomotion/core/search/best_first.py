"""Best-first state-space search with OPEN/CLOSED and re-parenting, paused and resumed.

Source: the ordered ("uspořádané") best-first search as given by Ondroušek & Březina
(paper 003, after Mařík 1993), steps 1-7:

1. Put the start state in OPEN; CLOSED is empty.
2. If OPEN is empty there is no solution: stop.
3. Take the state ``i`` with the least ``f(i)`` from OPEN; among ties prefer a goal state,
   otherwise any (here: the one generated first; :data:`.nodes.TieBreak` can change this).
4. Move ``i`` from OPEN to CLOSED.
5. If ``i`` is a goal, the solution is found: stop.
6. Expand ``i``; for each successor ``j`` compute ``f(j)``. A ``j`` in neither list goes to
   OPEN. A ``j`` already in OPEN or CLOSED with a larger value gets the new value and the new
   parent and goes (back) to OPEN.
7. Go to 2.

A* and weighted A* (:mod:`.astar`) are this search with ``f = g + w h``; ARA*
(:mod:`.ara_star`) runs it with an INCONS list instead of re-opening.

The state of a search is plain data (:class:`SearchState`: the nodes, the OPEN heap, the
CLOSED set, counters), so a driver can run it in batches, checkpoint it and resume it:
``run(1000)`` then ``run(2000)`` expands exactly what one ``run(2000)`` does. OPEN is a heap
with lazy deletion: an entry whose node has been closed or re-valued since is skipped.
"""

from __future__ import annotations

import heapq
import time
from collections.abc import Hashable
from dataclasses import dataclass, field
from typing import Any

from evomotion.core.search.nodes import (
    EXPANSION_BUDGET,
    FOUND,
    OPEN_EMPTY,
    TIME_BUDGET,
    Evaluate,
    LazyEvaluate,
    Node,
    OpenEntry,
    SearchProblem,
    SearchResult,
    TieBreak,
    frontier_min,
    goal_first,
    goal_first_deeper,
    is_ancestor,
    trace_plan,
)

_TIE_MODES: dict[Any, int] = {goal_first: 0, goal_first_deeper: 1}  # inlined in _expand
_GOAL_DEEP = goal_first_deeper(True, 0.0, None, None)


@dataclass
class SearchState:
    """Everything a search has done, as plain data (what a checkpoint stores)."""

    nodes: dict[Hashable, Node]
    open: list[OpenEntry]  # a heap; stale entries are skipped when popped
    closed: set[Hashable] = field(default_factory=set)
    incons: set[Hashable] | None = None  # ARA*'s INCONS (None: re-open instead)
    counter: int = 0  # OPEN entries made (the FIFO tie-break)
    expansions: int = 0  # states moved to CLOSED, goal included
    generated: int = 0
    reopened: int = 0
    reason: str | None = None  # FOUND / OPEN_EMPTY once the search has ended
    goal_key: Hashable | None = None
    last_f: float = 0.0  # f of the last entry taken from OPEN
    seconds: float = 0.0


class BestFirstSearch:
    """The paper's best-first search (steps 1-7 above) with the evaluation ``evaluate``.

    ``problem`` is a :class:`.nodes.SearchProblem`, optionally with lazy successors
    (:class:`.nodes.LazySuccessors`); a lazy child's f is ``f(parent) + lazy_delta`` when
    ``lazy_delta`` is given, else ``lazy_evaluate(...)``, else ``evaluate`` of the built child.
    A known state is re-parented only when its new value is lower by more than
    ``min_improvement``: evaluations that telescope along paths (the paper's (2) and (3))
    would otherwise re-parent on rounding noise and could close a parent cycle."""

    def __init__(self, problem: SearchProblem, evaluate: Evaluate, *,
                 lazy_evaluate: LazyEvaluate | None = None, lazy_delta: float | None = None,
                 tie_break: TieBreak = goal_first, min_improvement: float = 1e-9,
                 state: SearchState | None = None) -> None:
        self.problem, self.evaluate = problem, evaluate
        self.lazy_evaluate, self.lazy_delta = lazy_evaluate, lazy_delta
        self.tie_break, self.min_improvement = tie_break, min_improvement
        self.state = self.start_state() if state is None else state

    def start_state(self) -> SearchState:
        """OPEN holds the start state; CLOSED is empty (step 1)."""
        p = self.problem
        s0 = p.start()
        k0 = p.key(s0)
        f0 = self.evaluate(None, None, None, s0, None, 0.0)
        return SearchState({k0: Node(f0, 0.0, s0, None, None, 0.0)},
                           [(f0, self.tie_break(p.is_goal(s0), 0.0, k0, s0), 0, k0)],
                           last_f=f0)

    def run(self, max_expansions: int, max_seconds: float = float("inf")) -> str:
        """Expand until ``max_expansions`` in total (a goal, an empty OPEN, ``max_seconds`` of
        this call); returns the stop reason of this batch."""
        st = self.state
        if st.reason is not None:
            return st.reason
        t0 = time.perf_counter()
        nodes, heap, closed, is_goal = st.nodes, st.open, st.closed, self.problem.is_goal
        pop, clock, expand = heapq.heappop, time.perf_counter, self._expand
        p = self.problem
        lazy = getattr(p, "lazy_successors", None)  # optional (LazySuccessors)
        context = (nodes, heap, closed, st.incons, p.successors, p.key, is_goal, self.evaluate,
                   self.tie_break, _TIE_MODES.get(self.tie_break, 2), self.min_improvement, lazy,
                   None if lazy is None else p.build, self.lazy_evaluate,  # type: ignore
                   self.lazy_delta)
        reason = OPEN_EMPTY
        f, expansions = st.last_f, st.expansions
        try:
            while heap:
                if expansions >= max_expansions:
                    reason = EXPANSION_BUDGET
                    break
                if (expansions & 255) == 0 and clock() - t0 > max_seconds:
                    reason = TIME_BUDGET
                    break
                f, _, _, k = pop(heap)
                node = nodes[k]
                if k in closed or node.f != f:  # stale entry
                    continue
                closed.add(k)
                expansions += 1
                if is_goal(node.state):
                    reason, st.goal_key = FOUND, k
                    break
                expand(k, node, f, context)
        finally:
            st.last_f, st.expansions = f, expansions
            st.seconds += time.perf_counter() - t0
        if reason in (FOUND, OPEN_EMPTY):
            st.reason = reason
        return reason

    def _expand(self, k: Hashable, node: Node, f: float, context: tuple) -> None:
        """Step 6: value the successors of ``node`` (key ``k``, value ``f``); new or improved
        ones go to OPEN (improved CLOSED ones to INCONS in ARA*). ``context``: the tables and
        callables, bound once per :meth:`run`."""
        nodes, heap, closed, incons, successors, key_of, is_goal, evaluate, tie, mode, \
            min_imp, lazy_successors, build, lazy_eval, lazy_delta = context
        st, get, push = self.state, nodes.get, heapq.heappush
        counter, generated, reopened = st.counter, st.generated, st.reopened
        state, g = node.state, node.g
        for rule, child, step_cost in successors(state):
            generated += 1
            fc = evaluate(f, g, state, child, rule, step_cost)
            kc = key_of(child)
            gc = g + step_cost
            old = get(kc)
            if old is None:
                nodes[kc] = Node(fc, gc, child, k, rule, step_cost)
            elif fc < old.f - min_imp and not is_ancestor(nodes, kc, k):
                nodes[kc] = Node(fc, gc, child, k, rule, step_cost)
                if kc in closed:
                    if incons is not None:  # ARA*: no re-expansion this iteration
                        incons.add(kc)
                        continue
                    reopened += 1
                    closed.discard(kc)
            else:
                continue
            counter += 1
            goal = is_goal(child)  # the tie-breaks of .nodes, inlined for speed
            push(heap, (fc, (0 if goal else 1) if mode == 0 else (_GOAL_DEEP if goal else -gc)
                        if mode == 1 else tie(goal, gc, kc, child), counter, kc))
        if lazy_successors is not None:
            lazy = lazy_successors(state)
            generated += len(lazy)
            fl = None if lazy_delta is None else f + lazy_delta
            for rule, kc, step_cost, payload in lazy:
                if fl is not None:
                    fc = fl
                elif lazy_eval is not None:
                    fc = lazy_eval(f, g, state, payload, step_cost)
                else:
                    fc = evaluate(f, g, state, build(state, payload, kc), rule, step_cost)
                old = get(kc)
                if old is None:
                    gc = g + step_cost
                    nodes[kc] = Node(fc, gc, build(state, payload, kc), k, rule, step_cost)
                elif fc < old.f - min_imp and not is_ancestor(nodes, kc, k):
                    gc = g + step_cost
                    nodes[kc] = Node(fc, gc, build(state, payload, kc), k, rule, step_cost)
                    if kc in closed:
                        if incons is not None:
                            incons.add(kc)
                            continue
                        reopened += 1
                        closed.discard(kc)
                else:
                    continue
                counter += 1
                push(heap, (fc, 1 if mode == 0 else -gc if mode == 1 else tie(False, gc, kc, None),
                            counter, kc))
        st.counter, st.generated, st.reopened = counter, generated, reopened

    def result(self, reason: str | None = None) -> SearchResult:
        """The :class:`SearchResult` so far (plan traced when found); ``reason`` names a stop
        the search itself does not record (a budget)."""
        st = self.state
        result = SearchResult(st.reason or reason or EXPANSION_BUDGET, expansions=st.expansions,
                              generated=st.generated, reopened=st.reopened)
        if st.goal_key is not None:
            trace_plan(st.nodes, st.goal_key, result)
        else:
            result.frontier_f = frontier_min(st.nodes, st.open, st.closed)
        result.seconds = st.seconds
        return result


def best_first(problem: SearchProblem, evaluate: Evaluate, max_expansions: int = 1_000_000,
               max_seconds: float = float("inf"), min_improvement: float = 1e-9,
               **options: Any) -> SearchResult:
    """One :class:`BestFirstSearch` run to the end or the budgets (``max_expansions`` counts
    states moved to CLOSED, goal included; 0 expands nothing); ``options`` as its keywords."""
    search = BestFirstSearch(problem, evaluate, min_improvement=min_improvement, **options)
    reason = search.run(max_expansions, max_seconds)
    return search.result(reason)
