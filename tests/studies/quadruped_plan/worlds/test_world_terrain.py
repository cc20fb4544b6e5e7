"""Worlds, the planner's terrain checks against the independent checker, shifts, step back."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.errors import FileFormatError, InputError
from evomotion.studies.quadruped_plan.missions.recovery import STEP_BACK, step_back
from evomotion.studies.quadruped_plan.plans.checker import PlanViolationError, check_plan
from evomotion.studies.quadruped_plan.plans.plan import plan_document, world_section
from evomotion.studies.quadruped_plan.plans.planner import QuadrupedPlanConfig, make_problem
from evomotion.studies.quadruped_plan.rules.model import QuadrupedModel, lift_margin
from evomotion.studies.quadruped_plan.rules.rules import WalkProblem
from evomotion.studies.quadruped_plan.rules.shifts import SHIFT_MAX, shift_moves, shifted
from evomotion.studies.quadruped_plan.worlds.check import WorldGeometry
from evomotion.studies.quadruped_plan.worlds.terrain import Terrain
from evomotion.studies.quadruped_plan.worlds.world import bundled_worlds, load_world, read_world

TINY = Path(__file__).parents[1] / "data" / "tiny.world"
MODEL = QuadrupedModel()


def test_bundled_worlds_load_and_the_robot_can_stand_at_the_start():
    assert bundled_worlds() == ["corridor", "field", "gaps"]
    for name in bundled_worlds():
        w = load_world(name)
        t = Terrain(w, MODEL)
        assert t.stance_problem(MODEL.nominal_state(*w.start)) is None
        assert t.body_distance(*w.goal) > 0
    assert {p.kind for p in load_world("corridor").polygons} == {"obstacle", "hidden"}
    assert {p.kind for p in load_world("gaps").polygons} == {"nostep"}


def test_unknown_world_names_the_bundled_ones():
    with pytest.raises(InputError, match="unknown world 'moon'; available: corridor, field"):
        load_world("moon")


def test_a_start_on_an_obstacle_is_an_error_on_the_start_line(tmp_path):
    p = tmp_path / "bad.world"
    p.write_text("# comment\nstart 0 0 90\ngoal 10 0\nobstacle 1 -1  2 -1  2 1  1 1\n")
    cfg = QuadrupedPlanConfig(world=str(p))
    with pytest.raises(FileFormatError, match=r"bad.world:2: start: the robot cannot stand"):
        make_problem(cfg)


def test_world_settings_conflict_with_start_and_goal_keys():
    with pytest.raises(InputError, match="problem.goal_x: the world file gives"):
        make_problem(QuadrupedPlanConfig(world="gaps", goal_x=3.0))


def _doc(states: list[tuple], rules: list, world, extras=None, executed=True) -> dict:
    doc = plan_document(MODEL, states, rules, world.goal, 1e6, -1, "B", None, {},
                        world_section(world, 0.05, 0.05), extras)
    doc["executed"] = executed
    doc["disturbance_max"] = 0.3
    return doc


@settings(max_examples=60, deadline=None, derandomize=True)
@given(st.floats(-1.0, 9.0), st.floats(-3.0, 3.0), st.floats(0.0, 2 * math.pi))
def test_every_move_the_terrain_allows_passes_the_checker(x, y, phi):
    """Conservative checks: whatever the planner's terrain allows from a random stance near
    the tiny world's rock and puddle, the checker's exact geometry accepts."""
    world = read_world(TINY)
    terrain = Terrain(world, MODEL, world.of_kind("obstacle", "hidden"))
    problem = WalkProblem(MODEL, MODEL.nominal_state(x, y, phi), (10.0, 0.0), "B", 0.25, -1,
                          terrain=terrain, shifts=True)
    s0 = problem.start()
    if terrain.stance_problem(s0) is not None:
        return
    geo = WorldGeometry(world_section(world, 0.05, 0.05), MODEL.a, MODEL.b)
    for rule, child, _ in problem.successors(s0):
        b0, b1 = np.array(s0[:3]), np.array(child[:3])
        feet1 = terrain.world_feet(child)
        geo.check_feet(feet1, 0, f"rule {rule}", PlanViolationError)
        geo.check_body(geo.poses(b0, b1), 0, f"rule {rule}", PlanViolationError)


def test_the_checker_rejects_feet_in_no_step_zones_and_bodies_in_obstacles():
    world = read_world(TINY)
    s = MODEL.nominal_state(0.0, 0.0, math.pi / 2)
    into_rock = MODEL.nominal_state(4.7, 0.0, math.pi / 2)
    with pytest.raises(PlanViolationError, match="body overlaps an obstacle"):
        check_plan(_doc([into_rock], [0], world))
    near_puddle = MODEL.nominal_state(0.5, 1.5, math.pi / 2)  # a foot in the puddle
    with pytest.raises(PlanViolationError, match="inside a nostep polygon"):
        check_plan(_doc([near_puddle], [0], world))
    # a disturbance may move one foot, by at most disturbance_max
    slid = list(s)
    slid[3] += 0.5
    with pytest.raises(PlanViolationError, match="moved 0.500 in a slip"):
        check_plan(_doc([s, tuple(slid)], [0, 0], world,
                        [{"event": "start", "target": [10, 0]},
                         {"event": "slip 0", "target": [10, 0]}]))


def test_shift_frees_a_leg_and_step_back_keeps_the_feet():
    model = QuadrupedModel(min_margin=0.1)  # the nominal stance has margin 0: all blocked
    p = WalkProblem(model, model.nominal_state(0.0, 0.0, 1.0), (10.0, 0.0), "A", 0.25, -1,
                    shifts=True)
    s = p.start()
    blocked = [lift_margin(s, k) < model.min_margin for k in range(4)]
    assert all(blocked)
    moves = shift_moves(model, s, [not b for b in blocked])
    assert {rule - 28 for rule, _, _ in moves} <= {k for k in range(4) if blocked[k]}
    assert moves
    for rule, dx, dy in moves:
        child = shifted(s, dx, dy)
        assert math.hypot(dx, dy) <= SHIFT_MAX + 1e-12
        assert lift_margin(child, rule - 28) >= model.min_margin
        world_before = Terrain.world_feet(s)
        np.testing.assert_allclose(Terrain.world_feet(child), world_before, atol=1e-12)
    rules = {r for r, _, _ in p.successors(s)}
    assert rules & {28, 29, 30, 31}
    back = step_back(p, s)
    assert back is not None and back[0] < s[0] and back[1] > s[1]  # towards body +Y
    np.testing.assert_allclose(Terrain.world_feet(back), Terrain.world_feet(s), atol=1e-12)
    world = read_world(TINY)
    doc = plan_document(model, [s, back], [0, STEP_BACK], (0, 0), 1e6, -1, "A", None, {},
                        world_section(world, 0.05, 0.05))
    doc["executed"] = True
    check_plan(doc)
    doc["states"][1]["rule"] = 33
    with pytest.raises(PlanViolationError, match="no such rule"):
        check_plan(doc)
