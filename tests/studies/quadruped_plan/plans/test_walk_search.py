"""The specialised walking search gives exactly the generic core search's results."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from evomotion.core.search import astar, best_first
from evomotion.studies.quadruped_plan.plans.planner import QuadrupedPlanConfig, make_problem
from evomotion.studies.quadruped_plan.plans.search_config import SearchConfig
from evomotion.studies.quadruped_plan.plans.walk_search import walk_astar, walk_best_first
from evomotion.studies.quadruped_plan.rules.evaluation import paper_evaluation
from evomotion.studies.quadruped_plan.rules.heuristic import plan_length_heuristic
from evomotion.studies.quadruped_plan.rules.rules import KEY_WEIGHT, POS_GRID, WalkProblem


def _same(a, b) -> None:
    assert (a.stop_reason, a.expansions, a.generated, a.reopened) == \
        (b.stop_reason, b.expansions, b.generated, b.reopened)
    assert a.rules == b.rules and a.states == b.states
    assert a.cost == b.cost or (math.isnan(a.cost) and math.isnan(b.cost))
    assert a.frontier_f == b.frontier_f


CASES = [
    dict(rule_set="A", function=1, start_phi=math.pi / 4, goal_x=-3.0, goal_y=3.0),
    dict(rule_set="B", function=2, start_phi=1.5 * math.pi, goal_x=-4.0, goal_y=4.0),
    dict(rule_set="B", function=3, start_phi=1.5 * math.pi, goal_x=-5.0, goal_y=5.0),
    dict(rule_set="B", function=1, start_phi=0.0, goal_x=0.0, goal_y=-6.0, sense=0),
    dict(rule_set="B", function=3, start_phi=0.0, goal_x=2.0, goal_y=-6.0,
         zone_x=1.0, zone_y=-3.0, zone_radius=0.8),
    dict(rule_set="A", function=3, start_phi=0.0, goal_x=0.0, goal_y=-5.0, min_margin=0.1),
]


@pytest.mark.parametrize("case", CASES)
def test_walk_best_first_equals_core_best_first(case: dict) -> None:
    case = dict(case)
    search = SearchConfig(function=case.pop("function"), max_expansions=3000)
    cfg = replace(QuadrupedPlanConfig(), **case)
    ev = paper_evaluation(search.function, search.constants(cfg.rule_set),
                          (cfg.goal_x, cfg.goal_y), cfg.sense)
    fast = walk_best_first(make_problem(cfg), ev, search.max_expansions)
    ref = best_first(make_problem(cfg), ev, search.max_expansions)
    _same(fast, ref)
    # an evaluation without the leg shortcut builds the leg children: same again
    plain = walk_best_first(make_problem(cfg), lambda *a: ev(*a), search.max_expansions)
    _same(plain, ref)


@pytest.mark.parametrize(("rule_set", "weight", "sense"),
                         [("A", 1.0, -1), ("B", 2.0, -1), ("B", 1.0, 0)])
def test_walk_astar_equals_core_astar(rule_set: str, weight: float, sense: int) -> None:
    cfg = QuadrupedPlanConfig(start_phi=0.0, goal_x=0.5, goal_y=-4.5, rule_set=rule_set,
                              sense=sense)
    h = plan_length_heuristic(make_problem(cfg).model, (cfg.goal_x, cfg.goal_y),
                              cfg.goal_tolerance, sense)
    fast = walk_astar(make_problem(cfg), h, weight, max_expansions=4000)
    ref = astar(make_problem(cfg), h, weight, max_expansions=4000)
    _same(fast, ref)


def test_leg_targets_match_successors_and_packed_keys() -> None:
    cfg = QuadrupedPlanConfig(rule_set="B", zone_x=-1.0, zone_y=2.5, zone_radius=0.7)
    p: WalkProblem = make_problem(cfg)
    frontier, seen = [p.start()], 0
    q = 1.0 / POS_GRID
    while frontier and seen < 300:
        s = frontier.pop(0)
        kids = p.successors(s)
        legs = [(r, c) for r, c, _ in kids if r >= 4]
        assert [(r, c[11]) for r, c in legs] == [(t[0], t[4]) for t in p.leg_targets(s)]
        for _, c, _ in kids:
            # the packed key is the grid indices of the state, one field each
            fields = [round(c[i] * q) for i in (0, 1)] + [round((c[2] % (2 * math.pi)) / 1e-3)]
            fields += [round(c[i] * q) for i in range(3, 11)]
            assert c[11] == sum((v + (1 << 39)) * w for v, w in zip(fields, KEY_WEIGHT,
                                                                    strict=True))
            frontier.append(c)
            seen += 1
