"""The paper's experiment (section 4): 2 start states x 2 rule sets x functions (1)-(3).

Starts: phi0 = pi/4 ("a") and phi0 = 3/2 pi ("b"), legs nominal, goal (-10, 10). The paper
reports six of the twelve configurations (expanded states / plan states); the rest are new.
Every plan found is written to a plan document and re-verified by ``checker``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

from evomotion.studies.quadruped_plan.plans.checker import PlanViolationError, check_plan
from evomotion.studies.quadruped_plan.plans.plan import plan_document
from evomotion.studies.quadruped_plan.plans.planner import (
    QuadrupedPlanConfig,
    make_problem,
    solve,
)
from evomotion.studies.quadruped_plan.plans.search_config import SearchConfig

STARTS = {"a": math.pi / 4, "b": 1.5 * math.pi}
# (function, rule set, start) -> (expanded states, states in the plan) as printed in the paper
PAPER_FIGURES = {
    (1, "A", "a"): (284, 45), (1, "B", "b"): (18948, 211),
    (2, "A", "a"): (284, 45), (2, "B", "b"): (9072, 168),
    (3, "A", "a"): (39826, 40), (3, "B", "b"): (36672, 100),
}


@dataclass
class Row:
    method: str
    function: int | None
    rule_set: str
    start: str
    k: tuple[float, float, float] | None
    stop_reason: str
    expansions: int
    states: int
    leg_moves: int
    travel: float
    seconds: float
    check: str
    paper: tuple[int, int] | None  # the paper's figures (expanded / plan states), if printed
    bound: float = math.nan  # A* rows: proved lower bound on the least plan length

    @property
    def legs_per_unit(self) -> float:
        return self.leg_moves / self.travel if self.travel > 0 else math.nan


def run_config(cfg: QuadrupedPlanConfig, search: SearchConfig, start: str) -> Row:
    """Search one configuration (task ``cfg``, ``search``) and check its plan."""
    problem = make_problem(cfg)
    t0 = time.perf_counter()
    res = solve(cfg, search, problem)
    secs = time.perf_counter() - t0
    legs, travel, check = 0, 0.0, "-"
    if res.found:
        doc = plan_document(problem.model, res.states, res.rules, problem.goal,
                            cfg.goal_tolerance, cfg.sense, cfg.rule_set, problem.zone, {})
        try:
            summary = check_plan(doc)
            legs, travel, check = int(summary["leg_moves"]), summary["travel"], "ok"
        except PlanViolationError as e:
            check = f"FAIL: {e}"
    fn = search.function if search.method == "best-first" else None
    name = "A*" if search.method == "astar" else f"wA* w={search.weight:g}"
    name = search.method if fn else f"{name} {search.heuristic_gain[:4]}"
    return Row(name,
               fn, cfg.rule_set, start, search.constants(cfg.rule_set) if fn else None,
               res.stop_reason,
               res.expansions, len(res.states), legs, travel, secs, check,
               PAPER_FIGURES.get((fn, cfg.rule_set, start)) if fn else None, res.lower_bound)


def paper_table(base: QuadrupedPlanConfig | None = None, search: SearchConfig | None = None,
                astar_rows: bool = False, astar_seconds: float = 10.0,
                astar_grid: tuple[float, float] | None = None) -> list[Row]:
    """The 12 best-first configurations of task ``base`` (and, with ``astar_rows``, A* and
    weighted A* on the four start/rule-set pairs, each limited to ``astar_seconds`` and
    ``search.max_expansions``; their result column gives the proved lower bound on the least
    plan length).
    ``astar_grid`` = (pos_grid, angle_grid) replaces the duplicate grids of the A* rows only
    (their optimality and bounds then hold for that coarser duplicate detection)."""
    base, search = base or QuadrupedPlanConfig(), search or SearchConfig()
    rows = []
    for function in (1, 2, 3):
        for rule_set in ("A", "B"):
            for start, phi in STARTS.items():
                cfg = replace(base, rule_set=rule_set, start_phi=phi)
                rows.append(run_config(cfg, replace(search, function=function,
                                                    method="best-first"), start))
    if astar_rows:
        variants = (("astar", "analytic", 1.0), ("astar", "sampled", 1.0),
                    ("weighted-astar", "sampled", 2.0), ("weighted-astar", "analytic", 3.0))
        for method, gain, weight in variants:
            for rule_set in ("A", "B"):
                for start, phi in STARTS.items():
                    cfg = replace(base, rule_set=rule_set, start_phi=phi)
                    if astar_grid is not None:
                        cfg = replace(cfg, pos_grid=astar_grid[0], angle_grid=astar_grid[1])
                    rows.append(run_config(cfg, replace(search, method=method,
                                                        heuristic_gain=gain, weight=weight,
                                                        max_seconds=astar_seconds), start))
    return rows


def format_table(rows: list[Row]) -> str:
    head = (f"{'method':<16}{'fn':>3}{'set':>4}{'start':>6}  {'k1,k2,k3':<13}{'expanded':>9}"
            f"{'states':>7}{'legs':>5}{'legs/unit':>10}{'paper':>13}{'time s':>8}  result")
    lines = [head, "-" * len(head)]
    for r in rows:
        k = ",".join(f"{v:g}" for v in r.k) if r.k else "-"
        paper = f"{r.paper[0]}/{r.paper[1]}" if r.paper else "-"
        result = r.check if r.stop_reason == "found" else r.stop_reason
        if not math.isnan(r.bound):  # cost = states - 1 transitions
            result += f"; least cost >= {r.bound:.3g}"
        lines.append(f"{r.method:<16}{r.function or '-':>3}{r.rule_set:>4}{r.start:>6}  "
                     f"{k:<13}{r.expansions:>9}{r.states if r.states else '-':>7}"
                     f"{r.leg_moves if r.states else '-':>5}"
                     f"{r.legs_per_unit if r.states else math.nan:>10.2f}{paper:>13}"
                     f"{r.seconds:>8.2f}  {result}")
    return "\n".join(lines)
