"""The walking problem as a problem of the core search, with its leg moves built lazily.

The search is :mod:`evomotion.core.search` (the paper's best-first search, A*, weighted A*;
Ondroušek & Březina, paper 003); this module only adapts :class:`.rules.WalkProblem` to it.
About 9 in 10 successors of set B are leg moves onto an already known state, so leg moves
are *lazy successors*: a leg move's duplicate key is the parent's packed key plus one integer
(``WalkProblem.leg_options``, from the compiled ``_walkcore``) and its value is
``f(parent) + leg_delta`` (the paper's functions) or a cheap heuristic update
(``heuristic.after_leg``), so the child state tuple is built only when it enters OPEN.
``tests/studies/quadruped_plan/plans/test_walk_search.py`` checks that this gives exactly the plain
search's results (same successors in the same order, same values, same tie-breaking).
"""

from __future__ import annotations

from dataclasses import dataclass
from operator import itemgetter
from typing import Any

from evomotion.core.search import (
    BestFirstSearch,
    Evaluate,
    LazyEvaluate,
    SearchResult,
    astar_evaluation,
    with_lower_bound,
)
from evomotion.studies.quadruped_plan.rules.rules import WalkProblem

LEG_COST = 1.0  # every rule costs one transition


class WalkSpace:
    """A :class:`WalkProblem` for :class:`~evomotion.core.search.BestFirstSearch`: body moves
    are ordinary successors, leg moves lazy ones (payload: the compiled move ``(rule, fx, fy,
    key change)``, never a goal: they keep the body where the parent, not a goal, had it)."""

    def __init__(self, problem: WalkProblem) -> None:
        self.problem = problem
        self.start, self.is_goal = problem.start, problem.is_goal
        self.successors = problem.body_moves
        self.key = itemgetter(11)  # the packed duplicate key (WalkProblem.key)
        self._leg_options, self._parts = problem.leg_options, problem.parts

    def lazy_successors(self, s: tuple) -> list[tuple[int, int, float, tuple]]:
        """The leg moves, in the order of ``problem.leg_targets(s)``."""
        opts = self._leg_options(s)
        if not opts:
            return []
        key = s[11]
        return [(m[0], key + m[3], LEG_COST, m) for part in self._parts
                for _, moves in opts for m in moves[part]]

    @staticmethod
    def build(s: tuple, move: tuple[int, float, float, int], key: int) -> tuple:
        j = 3 + 2 * ((move[0] - 4) % 4)  # rule_leg
        return (*s[:j], move[1], move[2], *s[j + 2:11], key)


@dataclass(frozen=True)
class WalkEvaluation:
    """An evaluation for the walking search and its shortcut for leg moves (see module doc)."""

    evaluate: Evaluate
    lazy_evaluate: LazyEvaluate | None = None
    lazy_delta: float | None = None  # f(leg child) = f(parent) + lazy_delta

    def options(self) -> dict[str, Any]:
        return {"lazy_evaluate": self.lazy_evaluate, "lazy_delta": self.lazy_delta}


def walk_evaluation(evaluate: Evaluate | WalkEvaluation) -> WalkEvaluation:
    """``evaluate`` with its leg shortcut: the paper's functions carry ``leg_delta``
    (:mod:`.evaluation`); without one, leg children are built and evaluated."""
    if isinstance(evaluate, WalkEvaluation):
        return evaluate
    return WalkEvaluation(evaluate, lazy_delta=getattr(evaluate, "leg_delta", None))


def astar_evaluate(heuristic: Any, weight: float = 1.0) -> WalkEvaluation:
    """The (weighted) A* evaluation, with the leg shortcut when ``heuristic.after_leg`` exists:
    ``after_leg(s, leg, fy)`` (h of ``s`` with foot ``leg`` at body y ``fy``) evaluates leg
    children without building them."""
    evaluate = astar_evaluation(heuristic, weight)
    after_leg = getattr(heuristic, "after_leg", None)
    if after_leg is None:
        return WalkEvaluation(evaluate)

    def leg(pf: float, pg: float, ps: tuple, move: tuple, step_cost: float) -> float:
        return pg + step_cost + weight * after_leg(ps, (move[0] - 4) % 4, move[2])  # rule_leg

    return WalkEvaluation(evaluate, lazy_evaluate=leg)


def walk_search(problem: WalkProblem, evaluate: Evaluate | WalkEvaluation,
                min_improvement: float = 1e-9) -> BestFirstSearch:
    """A resumable best-first search of ``problem`` (``run(n)`` expands up to ``n`` in all)."""
    ev = walk_evaluation(evaluate)
    return BestFirstSearch(WalkSpace(problem), ev.evaluate, min_improvement=min_improvement,
                           **ev.options())


def walk_best_first(problem: WalkProblem, evaluate: Evaluate | WalkEvaluation,
                    max_expansions: int = 1_000_000, max_seconds: float = float("inf"),
                    min_improvement: float = 1e-9) -> SearchResult:
    """:func:`evomotion.core.search.best_first` on a :class:`WalkProblem` (same results)."""
    search = walk_search(problem, evaluate, min_improvement)
    reason = search.run(max_expansions, max_seconds)
    return search.result(reason)


def walk_astar(problem: WalkProblem, heuristic: Any, weight: float = 1.0,
               max_expansions: int = 1_000_000, max_seconds: float = float("inf")
               ) -> SearchResult:
    """:func:`evomotion.core.search.astar` on a :class:`WalkProblem` (same results, including
    ``lower_bound``)."""
    return with_lower_bound(walk_best_first(problem, astar_evaluate(heuristic, weight),
                                            max_expansions, max_seconds), weight)
