"""A* and weighted A*: best-first search with ``f = g + w h``, and its proved lower bound.

A* (Hart, Nilsson & Raphael 1968) is the best-first search of :mod:`.best_first` with
``f = g + h``; weighted A* (Pohl 1970) uses ``f = g + w h``. With an admissible ``h`` and
re-opening, A* returns a least-cost plan; weighted A* one within a factor ``w`` of it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from evomotion.core.search.best_first import best_first
from evomotion.core.search.nodes import OPEN_EMPTY, Evaluate, SearchProblem, SearchResult


def astar(problem: SearchProblem, heuristic: Callable[[Any], float], weight: float = 1.0,
          max_expansions: int = 1_000_000, max_seconds: float = float("inf"),
          **options: Any) -> SearchResult:
    """A* (``weight`` = 1) or weighted A* (``f = g + weight * h``) over ``problem``.

    ``heuristic(state)`` must be admissible (never above the least remaining cost) for A*
    to return a least-cost plan; re-opening of CLOSED states keeps this true when it is
    admissible but not consistent. ``options``: keywords of
    :class:`.best_first.BestFirstSearch` (lazy successors' evaluation, tie-break).

    ``lower_bound`` of the result: a cost that no plan can beat. While OPEN holds a node
    n of a least-cost plan with its least g (re-opening keeps one there), C* >= g(n) + h(n)
    >= (g(n) + weight h(n)) / weight >= min f on OPEN / weight; a found plan was that
    minimum (h = 0 at the goal), so C* >= cost / weight, i.e. cost <= weight C*.
    """
    return with_lower_bound(best_first(problem, astar_evaluation(heuristic, weight),
                                       max_expansions, max_seconds, **options), weight)


def with_lower_bound(result: SearchResult, weight: float) -> SearchResult:
    """Set ``result.lower_bound`` of an A* search with ``weight`` (see :func:`astar`)."""
    if result.found:
        result.lower_bound = result.cost / weight
    elif result.stop_reason != OPEN_EMPTY:
        result.lower_bound = result.frontier_f / weight
    return result


def astar_evaluation(heuristic: Callable[[Any], float], weight: float = 1.0) -> Evaluate:
    """The evaluation ``f = g + weight * h`` of (weighted) A* for the best-first search."""
    if weight < 1.0:
        raise ValueError(f"weighted A* needs weight >= 1, got {weight}")

    def evaluate(pf: Any, pg: Any, ps: Any, child: Any, rule: Any, step_cost: float) -> float:
        g = 0.0 if pg is None else pg + step_cost
        return g + weight * heuristic(child)

    return evaluate
