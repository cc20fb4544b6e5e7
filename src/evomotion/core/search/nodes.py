"""Search nodes, OPEN entries, stop reasons and results: what every search of :mod:`.` shares.

A node records how a state was reached (its evaluation ``f``, path cost ``g``, the parent's
duplicate key, the rule and its step cost); the OPEN list holds entries ``(f, tie, counter,
key)`` ordered by ``f``, then by the tie-break value, then by generation order (the counter),
so two runs of the same search expand the same states in the same order.
"""

from __future__ import annotations

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
# lazy_evaluate(parent_f, parent_g, parent_state, payload, step_cost) -> f of a lazy child
LazyEvaluate = Callable[[float, float, Any, Any, float], float]
# tie(is_goal, g, key, state) -> the second sort key of an OPEN entry (state None: lazy child)
TieBreak = Callable[[bool, float, Hashable, Any], Any]
# an OPEN entry: (f, tie, counter, key)
OpenEntry = tuple[float, Any, int, Hashable]


@dataclass(slots=True)
class Node:
    """One search node: ``state`` reached from ``parent`` (a key; None at the start) by
    ``rule`` at ``step_cost``, with evaluation ``f`` and path cost ``g``."""

    f: float
    g: float
    state: Any
    parent: Hashable | None
    rule: Any
    step_cost: float


def goal_first(goal: bool, g: float, key: Hashable, state: Any) -> int:
    """Ties of ``f``: a goal first, otherwise the state generated first (the paper's step 3)."""
    return 0 if goal else 1


def goal_first_deeper(goal: bool, g: float, key: Hashable, state: Any) -> float:
    """Ties of ``f``: a goal first, then the deeper state (larger ``g``); for plateaus of f."""
    return -float("inf") if goal else -g


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


class LazySuccessors(Protocol):
    """Optional extra successors whose state is built only when they enter OPEN.

    ``lazy_successors(state)`` lists ``(rule, child_key, step_cost, payload)`` after the
    ordinary successors; ``build(state, payload, child_key)`` makes the child state. A lazy
    child must not be a goal (its goal test waits until it is expanded)."""

    def lazy_successors(self, state: Any) -> Sequence[tuple[Any, Hashable, float, Any]]: ...

    def build(self, state: Any, payload: Any, key: Hashable) -> Any: ...


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
    # graph, (cost if found else frontier_f) / weight (see :func:`.astar.astar`); nan otherwise
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


def is_ancestor(nodes: dict[Hashable, Node], candidate: Hashable, k: Hashable | None) -> bool:
    """Whether ``candidate`` is ``k`` or one of its ancestors (re-parenting there would close a
    cycle: with a duplicate grid, a descendant can map to its ancestor's key)."""
    while k is not None:
        if k == candidate:
            return True
        k = nodes[k].parent
    return False


def trace_path(nodes: dict[Hashable, Node], key: Hashable) -> tuple[list[Any], list[Any], float]:
    """``(states, rules, cost)`` of the path from the start to ``key``, following parents.

    The cost is the traced path's own sum of step costs (a stored ``g`` can be stale below a
    re-parented node when ``f`` does not depend on ``g``, as with the paper's evaluation (1))."""
    states, rules = [], []
    cost = 0.0
    seen = set()
    k: Hashable | None = key
    while k is not None:
        if k in seen:  # a re-parenting cycle would be a bug in the evaluation
            raise RuntimeError("search tree has a parent cycle")
        seen.add(k)
        node = nodes[k]
        states.append(node.state)
        rules.append(node.rule)
        cost += node.step_cost
        k = node.parent
    return states[::-1], rules[::-1], cost


def trace_plan(nodes: dict[Hashable, Node], goal_key: Hashable, result: SearchResult) -> None:
    """Fill ``result.states``/``rules``/``cost`` with the path to ``goal_key``."""
    result.states, result.rules, result.cost = trace_path(nodes, goal_key)


def frontier_min(nodes: dict[Hashable, Node], open_list: list[OpenEntry],
                 closed: set[Hashable]) -> float:
    """The least f of the live (not stale) OPEN entries; inf when there are none."""
    live = [e[0] for e in open_list if e[3] not in closed and nodes[e[3]].f == e[0]]
    return min(live, default=float("inf"))
