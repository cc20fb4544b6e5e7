"""The compiled successors (_walkcore.c) are the Python ones: every body move and leg option of
states reached in the bundled worlds (rule sets A and B, with their terrains) and on the open
plane, the searches' results, and one-line errors for what is not a state."""

from __future__ import annotations

import math
import os
import random
import shutil
import sysconfig
from dataclasses import replace

import numpy as np
import pytest

from evomotion.studies.quadruped_plan.missions.mission import Mission
from evomotion.studies.quadruped_plan.plans.planner import QuadrupedPlanConfig, make_problem
from evomotion.studies.quadruped_plan.plans.search_config import SearchConfig
from evomotion.studies.quadruped_plan.plans.walk_search import walk_astar, walk_best_first
from evomotion.studies.quadruped_plan.rules import rules
from evomotion.studies.quadruped_plan.rules.evaluation import paper_evaluation
from evomotion.studies.quadruped_plan.rules.heuristic import plan_length_heuristic
from evomotion.studies.quadruped_plan.rules.model import QuadrupedModel
from evomotion.studies.quadruped_plan.rules.rules import WalkProblem
from evomotion.studies.quadruped_plan.worlds.world import bundled_worlds, load_world

compiled = pytest.mark.skipif(rules._walkcore is None, reason="_walkcore is not built here")


def test_the_core_is_built_where_a_compiler_is():
    """setup.py builds it (optional): with a C compiler and Python's headers it must exist."""
    if os.environ.get("EVOMOTION_PURE_PYTHON"):
        pytest.skip("EVOMOTION_PURE_PYTHON is set")
    headers = os.path.exists(os.path.join(sysconfig.get_paths()["include"], "Python.h"))
    if not (shutil.which("cc") or shutil.which("gcc")) or not headers:
        pytest.skip("no C compiler or no Python headers: the Python successors run")
    assert rules._walkcore is not None, "scripts/install.sh did not build _walkcore"


def _norm(x):
    """Lists and tuples alike (callers only iterate); floats bit for bit (-0.0 too)."""
    if isinstance(x, list | tuple):
        return tuple(_norm(v) for v in x)
    if isinstance(x, float):
        return ("float", x.hex())
    assert type(x) is int, type(x)
    return x


def _pair(p: WalkProblem) -> WalkProblem:
    return WalkProblem(p.model, p.start()[:11], p.goal, p.rule_set, p.goal_tolerance, p.sense,
                       p.zone, p.pos_grid, p.angle_grid, p.terrain, compiled=False)


def _check_states(p: WalkProblem, rng: random.Random, depth: int = 4, width: int = 12) -> int:
    ref = _pair(p)
    assert p.core and not ref.core
    frontier, n = [p.start()], 0
    for _ in range(depth):
        nxt = []
        for s in frontier:
            assert _norm(p.body_moves(s)) == _norm(ref.body_moves(s))
            assert _norm(p.leg_options(s)) == _norm(ref.leg_options(s))
            nxt += [c for _, c, _ in ref.successors(s)]
            n += 1
        frontier = rng.sample(nxt, min(len(nxt), width))
    return n


@compiled
@pytest.mark.parametrize("rule_set", ["A", "B"])
@pytest.mark.parametrize("world", bundled_worlds())
def test_successors_equal_the_python_ones_in_the_worlds(world, rule_set):
    m = Mission(load_world(world), QuadrupedModel(), rule_set)
    state = m.start()
    rng = random.Random(1)
    n = 0
    for k in range(3):  # the start and two stances part-way along the corridor of the world
        real = state.real
        if k:
            goal = state.goal
            real = m.model.nominal_state(real[0] + k * 0.3 * (goal[0] - real[0]),
                                         real[1] + k * 0.3 * (goal[1] - real[1]), real[2])
        p = m.problem(tuple(real), state.goal, 0.25, m.terrain(state, truth=True))
        n += _check_states(p, rng)
    assert n > 30


@compiled
@pytest.mark.parametrize("case", [dict(rule_set="A"), dict(rule_set="B"),
                                  dict(rule_set="B", sense=0, start_phi=0.3),
                                  dict(rule_set="A", min_margin=0.1, start_phi=2.0),
                                  dict(rule_set="B", pos_grid=0.05, angle_grid=0.01)])
def test_searches_on_the_plane_are_the_python_ones(case):
    cfg = replace(QuadrupedPlanConfig(goal_x=-4.0, goal_y=4.0), **case)
    p = make_problem(cfg)
    assert p.core
    _check_states(p, random.Random(2))
    ev = paper_evaluation(3, SearchConfig(function=3).constants(cfg.rule_set), p.goal, cfg.sense)
    a, b = walk_best_first(p, ev, 3000), walk_best_first(_pair(p), ev, 3000)
    assert (a.expansions, a.generated, a.rules, a.states) == \
        (b.expansions, b.generated, b.rules, b.states)
    h = plan_length_heuristic(p.model, p.goal, p.goal_tolerance, cfg.sense)
    a, b = walk_astar(p, h, 2.0, 3000), walk_astar(_pair(p), h, 2.0, 3000)
    assert (a.expansions, a.generated, a.rules, a.states) == \
        (b.expansions, b.generated, b.rules, b.states)


def test_zone_and_shifts_run_the_python_successors():
    cfg = QuadrupedPlanConfig(zone_x=-2.0, zone_y=2.0, zone_radius=0.5)
    assert not make_problem(cfg).core
    assert not make_problem(replace(cfg, zone_radius=0.0, shifts=True)).core


@compiled
def test_what_is_not_a_state_is_a_type_error():
    p = make_problem(QuadrupedPlanConfig())
    s = p.start()
    for bad in ("state", s[:5], (*s[:3], "x", *s[4:])):
        with pytest.raises(TypeError):
            p.body_moves(bad)
        with pytest.raises(TypeError):
            p.leg_options(bad)
    with pytest.raises(RuntimeError, match="not initialised"):
        rules._walkcore.WalkCore.__new__(rules._walkcore.WalkCore).body_moves(s)
    for bad_value in (math.nan, math.inf):  # an error from both, never silent results
        for i in (0, 2, 5):
            state = (*s[:i], bad_value, *s[i + 1:])
            for problem in (p, _pair(p)):
                with pytest.raises((ValueError, OverflowError)):
                    problem.body_moves(state)
                    problem.leg_options(state)
    core = rules._walkcore.WalkCore(*p._core_args())
    with pytest.raises(RuntimeError, match="once"):
        core.__init__(*p._core_args())
    assert _norm(core.body_moves(s)) == _norm(_pair(p).body_moves(s))


@compiled
def test_the_key_beyond_the_packed_range_is_still_the_python_key():
    """Coordinates beyond +-5e9 units (fields of more than 40 bits) take the slow path."""
    p = make_problem(QuadrupedPlanConfig())
    ref = _pair(p)
    far = p.make_state((6e9, -7e9, 1.0, *p.start()[3:11]))
    moves = p.body_moves(far)
    assert moves and _norm(moves) == _norm(ref.body_moves(far))
    assert _norm(p.leg_options(far)) == _norm(ref.leg_options(far))


@compiled
@pytest.mark.parametrize("world", bundled_worlds())
def test_body_moves_near_obstacles_equal_the_python_ones(world):
    """Random stances all over the world (many of them beside obstacles, where the body
    sweeps decide): the same moves, rules 1-3 (sense 0 too: either direction)."""
    w = load_world(world)
    m = Mission(w, QuadrupedModel(), "B")
    rng = np.random.default_rng(3)
    x0, y0, x1, y1 = w.bounds
    terrain = m.terrain(m.start(), truth=True)
    swept = 0
    for sense in (-1, 0):
        for _ in range(150):
            x, y = rng.uniform(x0, x1), rng.uniform(y0, y1)
            s0 = m.model.nominal_state(x, y, rng.uniform(-math.pi, math.pi))
            goal = (x + rng.uniform(-6, 6), y + rng.uniform(-6, 6))
            p = WalkProblem(m.model, s0, goal, "B", 0.25, sense, terrain=terrain)
            ref = _pair(p)
            s = p.start()
            assert _norm(p.body_moves(s)) == _norm(ref.body_moves(s))
            assert _norm(p.leg_options(s)) == _norm(ref.leg_options(s))
            swept += terrain.body_distance(x, y) < terrain.r_hip + 3.0
    assert swept > 20  # many of them near an obstacle


@compiled
def test_feet_far_away_and_a_foot_on_its_hip_are_the_python_results():
    """Leg-move keys of feet beyond 2^52 grid steps are exact Python ints; a foot on its
    hip (set B) is the Python code's ZeroDivisionError; a foot far on the wrong side of its
    hip is its math domain error."""
    p = make_problem(QuadrupedPlanConfig(rule_set="B"))
    ref = _pair(p)
    s = p.start()
    far = p.make_state((*s[:3], -1e15, *s[4:11]))
    assert _norm(p.leg_options(far)) == _norm(ref.leg_options(far))
    hx, hy = p.model.hips[0]
    on_hip = p.make_state((*s[:3], hx, hy, *s[5:11]))
    lift = rules._liftable(on_hip, p._stable)
    if lift[0]:
        for problem in (p, ref):
            with pytest.raises(ZeroDivisionError):
                problem.leg_options(on_hip)
    wrong = p.make_state((*s[:3], hx + 1.5, hy - 0.1, *s[5:11]))
    for problem in (p, ref):  # ux < -l_min below its hip: math.sqrt of a negative number
        with pytest.raises(ValueError, match="math domain error"):
            problem.body_moves(wrong)


@compiled
def test_bad_terrain_arguments_are_errors_not_crashes():
    w = load_world("corridor")
    m = Mission(w, QuadrupedModel(), "A")
    p = m.problem(tuple(m.start().real), w.goal, 0.25, m.terrain(m.start(), truth=True))
    args = list(p._core_args())
    t = list(args[4])
    for i, value in ((6, 2 ** 32), (7, 0), (16, -0.1), (17, math.nan), (13, -1)):
        bad = list(t)
        bad[i] = value
        with pytest.raises(ValueError):
            rules._walkcore.WalkCore(*args[:4], tuple(bad), args[5])
    bad = list(t)
    bad[1] = np.zeros(3)  # not the grid's size
    with pytest.raises(ValueError, match="grid's size"):
        rules._walkcore.WalkCore(*args[:4], tuple(bad), args[5])
