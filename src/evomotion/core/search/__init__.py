"""One state-space search for every study: best-first, A*, weighted A* and ARA*.

- :mod:`.nodes`: typed nodes, OPEN entries, tie-breaks, stop reasons, results, plan tracing;
- :mod:`.best_first`: the paper's best-first search with re-parenting, as a resumable object
  with plain-data state (:class:`SearchState`);
- :mod:`.astar`: A* and weighted A* (``f = g + w h``) and their lower bound;
- :mod:`.ara_star`: ARA* (Likhachev, Gordon & Thrun 2003).

The caller supplies the start, the successors (with step costs), the goal test, the duplicate
key and the evaluation or heuristic; nothing here knows a study.
"""

from evomotion.core.search.ara_star import (
    AraIteration,
    AraResult,
    AraStar,
    ara_star,
    open_lower_bound,
    reweight,
)
from evomotion.core.search.astar import astar, astar_evaluation, with_lower_bound
from evomotion.core.search.best_first import BestFirstSearch, SearchState, best_first
from evomotion.core.search.nodes import (
    EXPANSION_BUDGET,
    FOUND,
    OPEN_EMPTY,
    TIME_BUDGET,
    Evaluate,
    LazyEvaluate,
    LazySuccessors,
    Node,
    OpenEntry,
    SearchProblem,
    SearchResult,
    TieBreak,
    frontier_min,
    goal_first,
    goal_first_deeper,
    is_ancestor,
    trace_path,
    trace_plan,
)

__all__ = [
    "EXPANSION_BUDGET", "FOUND", "OPEN_EMPTY", "TIME_BUDGET", "AraIteration", "AraResult",
    "AraStar", "BestFirstSearch", "Evaluate", "LazyEvaluate", "LazySuccessors", "Node",
    "OpenEntry", "SearchProblem", "SearchResult", "SearchState", "TieBreak", "ara_star",
    "astar", "astar_evaluation", "best_first", "frontier_min", "goal_first",
    "goal_first_deeper", "is_ancestor", "open_lower_bound", "reweight", "trace_path",
    "trace_plan", "with_lower_bound",
]
