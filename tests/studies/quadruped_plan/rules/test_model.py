"""Geometry of the paper-003 quadruped: workspaces, stability, translation/rotation limits."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.studies.quadruped_plan.rules.model import (
    QuadrupedModel,
    lift_margin,
    rotation_limit,
    support_margin,
    translation_limit,
    world_feet,
)

M = QuadrupedModel()


def test_leg_corners_and_angles_follow_the_paper_table() -> None:
    assert M.hips == ((-1.25, 1.5), (-1.25, -1.5), (1.25, -1.5), (1.25, 1.5))
    assert M.min_angle(0) == M.min_angle(1) == 3 * math.pi / 4
    assert M.max_angle(0) == M.max_angle(1) == 5 * math.pi / 4
    assert M.min_angle(2) == math.pi / 4 and M.max_angle(3) == -math.pi / 4  # = 7/4 pi
    for leg in range(4):  # max angle = rear edge (body -Y), min angle = front edge
        assert M.foot_at(leg, 2, M.max_angle(leg))[1] < M.hips[leg][1]
        assert M.foot_at(leg, 2, M.min_angle(leg))[1] > M.hips[leg][1]


def test_workspace_membership() -> None:
    for leg in range(4):
        for length in (1.0, 1.5, 2.0):
            for beta in (M.min_angle(leg), M.nominal_angle(leg), M.max_angle(leg)):
                assert M.in_workspace(leg, *M.foot_at(leg, length, beta))
        assert not M.in_workspace(leg, *M.foot_at(leg, 0.9, M.nominal_angle(leg)))
        assert not M.in_workspace(leg, *M.foot_at(leg, 2.1, M.nominal_angle(leg)))
        assert not M.in_workspace(leg, *M.foot_at(leg, 1.5, M.nominal_angle(leg) + 0.9))
        assert not M.in_workspace(leg, *M.hips[leg])


def test_stability_margins() -> None:
    s = M.nominal_state(0, 0, 0)
    # symmetric stance: every lift puts the centre on a diagonal of the support
    assert all(abs(lift_margin(s, leg)) < 1e-12 for leg in range(4))
    assert support_margin(s) > 1.0
    # shift the feet back: front legs can no longer be lifted, rear legs can
    back = (*s[:3], *[v - 0.5 * (k % 2) for k, v in enumerate(s[3:])])
    assert lift_margin(back, 0) < 0 and lift_margin(back, 3) < 0
    assert lift_margin(back, 1) > 0 and lift_margin(back, 2) > 0


def test_world_feet_rotate_with_the_body() -> None:
    s = M.nominal_state(1.0, 2.0, math.pi / 2)
    f = world_feet(s)
    assert np.allclose(f[0], (1.0 - 1.5, 2.0 - 2.75))  # body +Y is world -X


feasible = st.tuples(*[st.tuples(st.floats(1.0, 2.0), st.floats(-0.78, 0.78))
                       for _ in range(4)])


def _state(polars: tuple) -> tuple[float, ...]:
    feet = []
    for leg, (length, off) in enumerate(polars):
        feet += M.foot_at(leg, length, M.nominal_angle(leg) + off)
    return (0.0, 0.0, 0.0, *feet)


def _inside(feet: np.ndarray) -> bool:
    return all(M.in_workspace(leg, *feet[leg], tol=1e-7) for leg in range(4))


@settings(max_examples=80, deadline=None)
@given(feasible, st.sampled_from([-1.0, 1.0]))
def test_translation_limit_matches_sampled_path(polars: tuple, sign: float) -> None:
    s = _state(polars)
    t = translation_limit(M, s, sign)
    feet = np.array(s[3:]).reshape(4, 2)
    for u in np.linspace(0, 1, 200):  # every point up to the limit is inside
        assert _inside(feet - [0, sign * t * u])
    beyond = feet - [0, sign * (t + 0.02)]
    assert not all(_inside(feet - [0, sign * v]) for v in np.linspace(t, t + 0.02, 50)) \
        or not _inside(beyond)


def _rotated(feet: np.ndarray, angle: float) -> np.ndarray:
    c, s = math.cos(-angle), math.sin(-angle)
    return feet @ np.array([[c, s], [-s, c]])


@settings(max_examples=80, deadline=None)
@given(feasible, st.sampled_from([-1.0, 1.0]))
def test_rotation_limit_matches_sampled_arc(polars: tuple, direction: float) -> None:
    s = _state(polars)
    r = min(rotation_limit(M, s, direction), math.pi)
    feet = np.array(s[3:]).reshape(4, 2)
    for u in np.linspace(0, 1, 200):
        assert _inside(_rotated(feet, direction * r * u))
    if r < math.pi:
        assert not all(_inside(_rotated(feet, direction * v))
                       for v in np.linspace(r, r + 0.02, 50))


@settings(max_examples=60, deadline=None)
@given(feasible, st.floats(-0.5, 0.5))
def test_fast_lift_check_matches_reference_margin(polars: tuple, threshold: float) -> None:
    from evomotion.studies.quadruped_plan.rules.rules import _liftable

    s = _state(polars)
    fast = _liftable(s, threshold)
    for leg in range(4):
        m = lift_margin(s, leg)
        if abs(m - threshold) > 1e-9:
            assert fast[leg] == (m >= threshold)
