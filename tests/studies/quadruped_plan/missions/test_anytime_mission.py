"""ARA*, the heuristic's consistency, the receding-horizon walker and its one-shot baseline."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from evomotion.studies.quadruped_plan.missions.doc import mission_document
from evomotion.studies.quadruped_plan.missions.mission import (
    Disturbances,
    Mission,
    run_mission,
    summary,
)
from evomotion.studies.quadruped_plan.missions.oneshot import one_shot, plan_once
from evomotion.studies.quadruped_plan.plans.anytime import ara_star
from evomotion.studies.quadruped_plan.plans.checker import check_plan
from evomotion.studies.quadruped_plan.plans.walk_search import walk_astar
from evomotion.studies.quadruped_plan.rules.heuristic import plan_length_heuristic
from evomotion.studies.quadruped_plan.rules.model import QuadrupedModel
from evomotion.studies.quadruped_plan.rules.rules import WalkProblem
from evomotion.studies.quadruped_plan.worlds.world import read_world

TINY = Path(__file__).parents[1] / "data" / "tiny.world"
MODEL = QuadrupedModel()


def _problem(goal=(0.0, -4.0), rule_set="A", shifts=False, model=MODEL, phi=0.0):
    return WalkProblem(model, model.nominal_state(0.0, 0.0, phi), goal, rule_set, 0.25, -1,
                       shifts=shifts)


@pytest.mark.parametrize(("rule_set", "gain", "shifts"),
                         [("A", "analytic", False), ("B", "sampled", False),
                          ("B", "analytic", True)])
def test_the_heuristic_drops_by_at_most_one_per_rule(rule_set, gain, shifts):
    """Consistency without shifts (what ARA*'s bound needs): h(s) <= 1 + h(s') for every
    rule, on the states of a random walk; with shifts, at least admissible along it."""
    model = QuadrupedModel(min_margin=0.1) if shifts else MODEL
    p = _problem((-8.0, 8.0), rule_set, shifts, model, 1.5 * math.pi)
    h = plan_length_heuristic(model, p.goal, p.goal_tolerance, -1, gain, shifts)
    rng = np.random.default_rng(1)
    s = p.start()
    worst = -math.inf
    for _ in range(300):
        succ = p.successors(s)
        if not succ:
            break
        for _, child, _ in succ:
            worst = max(worst, h(s) - h(child))
        s = succ[int(rng.integers(len(succ)))][1]
    if not shifts:
        assert worst <= 1.0
    assert h(p.start()) <= 60  # and the admissibility checks below


def test_ara_star_reaches_the_optimum_with_its_bound():
    p = _problem((0.0, -4.0), "A")
    h = plan_length_heuristic(MODEL, p.goal, p.goal_tolerance, -1, "analytic")
    exact = walk_astar(p, h, 1.0, 200_000)
    plan = ara_star(p, h, 200_000)
    assert exact.found and plan.complete and plan.stop == "optimal"
    assert plan.cost == exact.cost and plan.bound == 1.0
    # a small budget: a plan (or a partial one) and an honest bound
    small = ara_star(p, h, 300)
    assert small.expansions <= 300
    if small.complete:
        assert small.bound >= 1.0 and small.cost <= small.bound * exact.cost + 1e-9
    else:
        assert len(small.states) >= 1 and small.bound == math.inf
    # admissible with shifts: h at the start never exceeds A*'s least cost
    model = QuadrupedModel(min_margin=0.1)
    ps = _problem((0.0, -4.0), "A", True, model)
    hs = plan_length_heuristic(model, ps.goal, ps.goal_tolerance, -1, "analytic", True)
    opt = walk_astar(ps, hs, 1.0, 200_000)
    assert opt.found and hs(ps.start()) <= opt.cost


def test_ara_star_with_a_first_plan_keeps_the_shorter_one():
    from evomotion.studies.quadruped_plan.rules.evaluation import PAPER_CONSTANTS, paper_evaluation

    p = _problem((1.0, -5.0), "B")
    h = plan_length_heuristic(MODEL, p.goal, p.goal_tolerance, -1, "analytic")
    first = paper_evaluation(3, PAPER_CONSTANTS[(3, "B")], p.goal, -1)
    both = ara_star(p, h, 20_000, first=first)
    alone = ara_star(p, h, 20_000, weights=(), first=first)
    assert both.complete and alone.complete and both.cost <= alone.cost


def test_a_walk_is_deterministic_checked_and_disturbed():
    world = read_world(TINY)
    m = Mission(world, MODEL, "B")
    a = run_mission(m, np.random.default_rng(0))
    b = run_mission(Mission(world, MODEL, "B"), np.random.default_rng(0))
    assert a.path == b.path and a.done == "reached"
    s = summary(a)
    assert s["reached"] and s["replans"] >= 3 and s["events"] >= 3
    events = {p["event"] for p in a.path}
    assert "landing" in events and any(e.startswith("slip") for e in events)
    assert a.revealed == (0,) and a.goal_moved_at > 0 and a.goal != world.goal
    doc = mission_document(m, a)
    out = check_plan(doc)
    assert out["states"] == len(a.path)
    assert doc["goal_history"][1]["from"] == a.goal_moved_at
    c = run_mission(Mission(world, MODEL, "B"), np.random.default_rng(1))
    assert c.path != a.path


def test_without_disturbances_the_walk_is_the_one_shot_plan():
    world = read_world(TINY)
    quiet = Disturbances(0.0, 0.0, 0.0, 0.0, 0.0)
    m = Mission(world, MODEL, "A", disturb=quiet)
    walk = run_mission(m, np.random.default_rng(0))
    assert walk.done == "reached"
    assert not any(p["event"] not in ("", "start") for p in walk.path)
    planned = plan_once(m, 1_000)
    shot = one_shot(m, np.random.default_rng(0), planned)
    assert shot["reached"] and shot["planned_transitions"] > 0
    disturbed = one_shot(Mission(world, MODEL, "A"), np.random.default_rng(0), planned)
    assert disturbed["outcome"]  # reached or a one-line failure


def test_the_time_budget_is_counted_as_not_reproducible():
    world = read_world(TINY)
    m = Mission(world, MODEL, "B")
    from dataclasses import replace

    m = replace(m, settings=replace(m.settings, replan_ms=1e-6, max_replans=3))
    st = run_mission(m, np.random.default_rng(0))
    assert st.time_bound == st.replans == 3
