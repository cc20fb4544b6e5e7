"""The quadruped-plan search as a driver: best-first / A* stepped in batches of expansions.

``[algorithm]`` is ``name = "search"`` (:class:`.search_config.SearchConfig`): the method, the
paper's function, the budgets and ``batch_expansions`` (expansions per step); the task
(``[problem]``) says which plan is searched for. One step expands up to ``batch_expansions``
more states, so a run logs, stops, checkpoints (the OPEN/CLOSED lists as arrays,
:mod:`.search_state`) and resumes like any other; the expansions are what ``stats.csv`` counts
as evaluations. A search has no batch evaluation to distribute, so only the serial evaluator
applies.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from evomotion.core.problem import Sense
from evomotion.core.search import (
    FOUND,
    OPEN_EMPTY,
    BestFirstSearch,
    SearchResult,
    with_lower_bound,
)
from evomotion.run.driver import Driver, Evaluate, StepReport
from evomotion.studies.quadruped_plan.plans.planner import (
    QuadrupedPlanConfig,
    unreachable_reason,
)
from evomotion.studies.quadruped_plan.plans.search_config import SearchConfig
from evomotion.studies.quadruped_plan.plans.search_state import search_from_arrays, search_to_arrays
from evomotion.studies.quadruped_plan.plans.walk_search import astar_evaluate, walk_search
from evomotion.studies.quadruped_plan.rules.evaluation import paper_evaluation
from evomotion.studies.quadruped_plan.rules.heuristic import plan_length_heuristic
from evomotion.studies.quadruped_plan.rules.rules import WalkProblem

EXTRA_COLUMNS = ("open", "nodes", "generated", "reopened")


@dataclass
class SearchDriverState:
    search: BestFirstSearch
    unreachable: str | None = None


class SearchDriver(Driver):
    sense: Sense = "min"
    extra_columns = EXTRA_COLUMNS
    uses_evaluator = False
    snapshot_every_step = False

    def __init__(self, problem: WalkProblem, task: QuadrupedPlanConfig,
                 search: SearchConfig) -> None:
        search.validate()
        self.problem, self.task, self.cfg = problem, task, search
        self.batch = search.batch_expansions
        self.weight = 1.0 if search.method == "astar" else search.weight

    def _evaluate(self):
        cfg, sense = self.cfg, self.task.sense
        if cfg.method == "best-first":
            return paper_evaluation(cfg.function, cfg.constants(self.task.rule_set),
                                    self.problem.goal, sense)
        h = plan_length_heuristic(self.problem.model, self.problem.goal,
                                  self.problem.goal_tolerance, sense, cfg.heuristic_gain,
                                  self.problem.shifts)
        return astar_evaluate(h, self.weight)

    def init(self, rng: np.random.Generator) -> SearchDriverState:
        return SearchDriverState(walk_search(self.problem, self._evaluate()),
                                 unreachable_reason(self.task))

    def step(self, state: SearchDriverState, rng: np.random.Generator,
             evaluate: Evaluate) -> tuple[SearchDriverState, StepReport]:
        s = state.search.state
        if state.unreachable is not None:
            return state, StepReport(0, np.array([np.inf]), lines=[state.unreachable])
        before = s.expansions
        target = min(before + self.batch, self.cfg.max_expansions)
        state.search.run(target, max(self.cfg.max_seconds - s.seconds, 0.0))
        extras = {"open": len(s.open), "nodes": len(s.nodes), "generated": s.generated,
                  "reopened": s.reopened}
        return state, StepReport(s.expansions - before, np.array([s.last_f]), extras=extras)

    def stop(self, state: SearchDriverState) -> str | None:
        s = state.search.state
        if state.unreachable is not None:
            return "unreachable"
        if s.reason == FOUND:
            return "found"
        if s.reason == OPEN_EMPTY:
            return "open-empty"
        if s.expansions >= self.cfg.max_expansions:
            return "expansion-budget"
        if s.seconds >= self.cfg.max_seconds:
            return "time-budget"
        return None

    def result(self, state: SearchDriverState) -> SearchResult:
        reason = self.stop(state)
        res = state.search.result(reason if reason in ("expansion-budget", "time-budget")
                                  else None)
        return res if self.cfg.method == "best-first" else with_lower_bound(res, self.weight)

    def best(self, state: SearchDriverState) -> tuple[np.ndarray, float]:
        s = state.search.state
        if s.goal_key is None:
            return np.zeros(0), float("inf")
        n, k = 0, s.goal_key
        while s.nodes[k].parent is not None:
            n, k = n + 1, s.nodes[k].parent
        return np.zeros(0), float(n)  # plan length in transitions

    def state_arrays(self, state: SearchDriverState
                     ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        a, m = search_to_arrays(state.search)
        return a, dict(m, unreachable=state.unreachable)

    def restore(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]
                ) -> SearchDriverState:
        fresh = walk_search(self.problem, self._evaluate())
        return SearchDriverState(search_from_arrays(fresh, arrays, meta), meta.get("unreachable"))


def make_driver(problem: WalkProblem, config: Any) -> SearchDriver:
    return SearchDriver(problem, config.problem, config.algorithm)
