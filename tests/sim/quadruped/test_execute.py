"""Executing plans: standing still, short real paper-003 plans, bad input, the result format."""

import json
import math

import numpy as np
import pytest

from evomotion.sim.quadruped import QuadrupedSpec, execute_plan, plan_qpos
from evomotion.sim.quadruped.trajectory import build_timeline
from evomotion.studies.quadruped_plan.plans.plan import plan_document
from evomotion.studies.quadruped_plan.plans.planner import QuadrupedPlanConfig, make_problem, solve
from evomotion.studies.quadruped_plan.plans.search_config import SearchConfig

SPEC = QuadrupedSpec()
#: rule set B, function 3: 13 states, margins >= 0.04 units (task, search)
SHORT_B = (QuadrupedPlanConfig(start_phi=0.0, goal_x=0.0, goal_y=-3.0, rule_set="B"),
           SearchConfig(function=3, max_seconds=20.0))
#: rule set A, function 1 (the paper's): lifts with margin 0; the first 25 states
SHORT_A = (QuadrupedPlanConfig(start_phi=math.pi / 4, goal_x=-2.0, goal_y=2.0, rule_set="A"),
           SearchConfig(function=1, max_seconds=20.0))
POSITION_BOUND_M = 0.02  # final torso position error allowed on the short plans


def _states(case: tuple[QuadrupedPlanConfig, SearchConfig], n: int | None = None
            ) -> list[dict]:
    cfg, search = case
    p = make_problem(cfg)
    res = solve(cfg, search, p)
    assert res.found
    doc = plan_document(p.model, res.states, res.rules, p.goal, cfg.goal_tolerance, cfg.sense,
                        cfg.rule_set, None, {})
    return doc["states"][:n]


def _nominal() -> dict:
    return _states(SHORT_B, 1)[0]


def test_stands_still_for_two_seconds() -> None:
    res = execute_plan([_nominal()], settle_seconds=2.0, final_seconds=0.0)
    assert res.body_up and not res.body_floor_contact and not res.diverged
    assert res.duration_s >= 2.0
    assert res.min_body_height_m > 0.95 * SPEC.body_height_m
    assert res.max_tilt_rad < 1e-3 and res.final_position_error_m < 1e-3
    assert res.min_support_margin_m > 0.1  # nominal stance: centre 0.15 m inside


@pytest.mark.parametrize(("cfg", "n"), [(SHORT_B, None), (SHORT_A, 25)], ids=["B", "A25"])
def test_short_real_plan_keeps_the_body_up(cfg: QuadrupedPlanConfig, n: int | None) -> None:
    states = _states(cfg, n)
    res = execute_plan(states)
    assert not res.diverged and res.body_up, res
    assert res.final_position_error_m < POSITION_BOUND_M
    assert res.final_heading_error_rad < 0.1
    assert len(res.transition_margins_m) == len(states) - 1
    assert res.min_support_margin_m >= -1e-9  # the COP never leaves the contact hull
    doc = json.loads(json.dumps(res.to_dict(), allow_nan=False))
    assert doc["steps"] == res.steps and doc["body_up"] is True


def test_multi_change_transition_swings_each_foot_then_moves_the_body() -> None:
    s0 = _nominal()
    feet = np.array(s0["feet"])
    shift = np.array([[0.0, -0.3], [0.0, -0.3], [0.0, 0.0], [0.0, 0.0]])  # legs 0, 1
    s1 = {"body": [0.0, -0.3, 0.0], "feet": (feet + shift).tolist(), "rule": 0}
    tl = build_timeline(SPEC, [s0, s1], leg_seconds=0.5, metres_per_second=0.05,
                        radians_per_second=0.5, lift_m=0.01, settle_seconds=0.1,
                        final_seconds=0.1)
    assert tl.segments == [("leg", 0, 0), ("leg", 0, 1), ("body", 0, -1)]
    res = execute_plan([s0, s1])
    assert res.body_up and res.final_position_error_m < 0.01


def test_nan_input_reports_diverged() -> None:
    s0 = _nominal()
    bad = {"body": [float("nan"), 0.0, 0.0], "feet": s0["feet"], "rule": 1}
    res = execute_plan([s0, bad])
    assert res.diverged and not res.body_up and res.steps == 0
    assert res.to_dict()["min_body_height_m"] is None
    qpos, dt = plan_qpos([s0, bad])
    assert qpos.shape == (0, 19) and dt == SPEC.timestep


def test_unstable_simulation_reports_diverged(tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)  # MuJoCo's warning writes MUJOCO_LOG.TXT to the cwd
    stiff = QuadrupedSpec(kp=1e7, kv=0.0, armature=1e-7, timestep=0.02)  # explodes at once
    res = execute_plan(_states(SHORT_B, 3), stiff)
    assert res.diverged and not res.body_up and res.steps > 0
