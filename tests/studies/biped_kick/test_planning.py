"""Kick-point choice, Bézier approach and the baseline comparison; kick-plan.png."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.studies.biped_kick.planning import (
    baseline_time,
    bezier,
    bezier_time,
    kick_costs,
    plan_kick,
    wrap,
)
from evomotion.studies.biped_kick.views import plot_kick_plan

BALL, GOAL = np.array([1.5, 0.5]), np.array([4.5, 0.0])


def cross2(a: np.ndarray, b: np.ndarray) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def test_robot_behind_ball_picks_the_point_on_the_goal_line():
    # robot on the extended goal->ball line, facing the goal: no turning needed
    u = (GOAL - BALL) / np.linalg.norm(GOAL - BALL)
    start = BALL - 1.0 * u
    robot = np.array([*start, np.arctan2(u[1], u[0])])
    plan = plan_kick(robot, BALL, GOAL, radius_m=0.2, n=37)
    assert np.allclose(plan.kick_point, BALL - 0.2 * u, atol=1e-9)
    length, t = bezier_time(plan.control_points)
    assert np.isclose(length, 0.8, atol=1e-6)  # a straight path
    assert np.isclose(t, 0.8 / 0.2, rtol=1e-6)


@settings(max_examples=30, deadline=None)
@given(x=st.floats(-2, 1), y=st.floats(-2, 2), th=st.floats(-np.pi, np.pi))
def test_plan_invariants(x, y, th):
    robot = np.array([x, y, th])
    if np.linalg.norm(robot[:2] - BALL) < 0.4:
        return
    plan = plan_kick(robot, BALL, GOAL, radius_m=0.2)
    assert np.isclose(np.linalg.norm(plan.kick_point - BALL), 0.2)
    assert plan.cost[plan.best] == plan.cost.min()
    c = plan.control_points
    # P1 on the robot heading, P2 on the kick line behind the kick point
    h = np.array([np.cos(th), np.sin(th)])
    assert np.isclose(cross2(h, c[1] - c[0]), 0, atol=1e-9) and (c[1] - c[0]) @ h >= 0
    u_k = (BALL - plan.kick_point) / 0.2
    assert np.isclose(cross2(u_k, c[3] - c[2]), 0, atol=1e-9) and (c[3] - c[2]) @ u_k >= 0
    p = bezier(c, np.array([0.0, 1.0]))
    assert np.allclose(p, c[[0, 3]])
    length, t = bezier_time(c)
    chord = np.linalg.norm(c[3] - c[0])
    assert length >= chord - 1e-9 and t >= length / 0.2 - 1e-9
    bl_len, bl_t = baseline_time(robot, plan)
    assert np.isclose(bl_len, chord)


def test_bezier_faster_than_turn_walk_align_when_turning_is_needed():
    robot = np.array([0.0, -1.0, np.pi / 2])  # facing +y, ball ahead-right
    plan = plan_kick(robot, BALL, GOAL)
    _, t_bz = bezier_time(plan.control_points)
    _, t_bl = baseline_time(robot, plan)
    assert t_bz < t_bl


def test_costs_and_wrap():
    K, phi, c_turn, c_dist = kick_costs(np.array([0, 0, 0.0]), BALL, GOAL, n=5)
    assert K.shape == (5, 2) and np.all(c_turn >= 0) and np.all(c_dist > 0)
    assert np.allclose(wrap(np.array([3 * np.pi, -3 * np.pi / 2])), [np.pi, np.pi / 2])


def test_kick_plan_png(tmp_path):
    out = tmp_path / "kick-plan.png"
    res = plot_kick_plan(np.array([0.0, -1.0, np.pi / 2]), BALL, GOAL, out)
    assert out.stat().st_size > 10_000
    assert res["bezier_time_s"] < res["baseline_time_s"]


def test_plan_command_writes_png(tmp_path):
    from typer.testing import CliRunner

    from evomotion.studies.biped_kick.study import cli

    out = tmp_path / "plan.png"
    res = CliRunner().invoke(cli, ["plan", "--out", str(out), "--radius", "0.25"])
    assert res.exit_code == 0 and "bezier_time_s=" in res.output
    assert out.exists()
    bad = CliRunner().invoke(cli, ["plan", "--out", str(out), "--radius", "-1"])
    assert bad.exit_code != 0
