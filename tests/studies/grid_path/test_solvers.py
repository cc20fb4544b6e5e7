"""Exact solvers against brute-force references, and the bundled maps' paper optima."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gp_reference import octile_reference, valid_reference, visibility_reference
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.studies.grid_path.maps import GridMap, connected
from evomotion.studies.grid_path.problem import load_map
from evomotion.studies.grid_path.solvers import (
    all_optima,
    centres_optimum,
    free_optimum,
    obstacle_corners,
    octile_astar,
)

SQ2 = math.sqrt(2)


@st.composite
def small_maps(draw):
    w, h = draw(st.integers(2, 5)), draw(st.integers(2, 5))
    cells = draw(st.lists(st.booleans(), min_size=w * h, max_size=w * h))
    b = np.array(cells, bool).reshape(h, w)
    b[0, 0] = b[h - 1, w - 1] = False
    if not connected(b, (0, 0), (w - 1, h - 1)):
        b[:, :] = False
    return GridMap(b, (0, 0), (w - 1, h - 1))


@settings(max_examples=15, deadline=None)
@given(small_maps())
def test_three_models_match_bruteforce(m):
    o = all_optima(m)
    assert o["octile"].length == pytest.approx(octile_reference(m.blocked, m.start, m.goal))
    assert o["octile"].length == pytest.approx(o["octile"].n_straight
                                               + o["octile"].n_diagonal * SQ2, abs=1e-12)
    ys, xs = np.nonzero(~m.blocked)
    centres = [(x + 0.5, y + 0.5) for x, y in zip(xs, ys, strict=True)]
    s, t = centres.index(tuple(m.start_xy)), centres.index(tuple(m.goal_xy))
    assert o["centres"].length == pytest.approx(
        visibility_reference(m.blocked, centres, s, t, "closed"))
    # free model: all lattice points (a superset of the corners) plus S and G
    lattice = [tuple(m.start_xy), tuple(m.goal_xy)] + [
        (x, y) for y in range(m.height + 1) for x in range(m.width + 1)]
    assert o["free"].length == pytest.approx(
        visibility_reference(m.blocked, lattice, 0, 1, "open"))
    assert o["free"].length <= o["centres"].length + 1e-9 <= o["octile"].length + 2e-9
    for sol, rule in ((o["centres"], "closed"), (o["free"], "open")):
        w = sol.waypoints
        assert all(valid_reference(m.blocked, a, b, rule) for a, b in zip(w[:-1], w[1:],
                                                                          strict=True))
        assert np.hypot(*np.diff(w, axis=0).T).sum() == pytest.approx(sol.length)


@pytest.mark.parametrize(("name", "ns", "nd"), [("seed10a", 4, 7), ("seed10b", 4, 7),
                                                ("seed15", 8, 10), ("seed20", 12, 13)])
def test_bundled_maps_have_the_paper_optima(name, ns, nd):
    o = octile_astar(load_map(name))
    assert (o.n_straight, o.n_diagonal) == (ns, nd)
    assert round(o.length, 4) == {7: 13.8995, 10: 22.1421, 13: 30.3848}[nd]


def test_known_small_cases():
    b = np.zeros((3, 3), bool)
    b[1, 1] = True
    m = GridMap(b, (0, 0), (2, 2))
    assert octile_astar(m).length == pytest.approx(4.0)  # no corner cutting past the block
    assert centres_optimum(m).length == pytest.approx(4.0)  # touching its corner is invalid
    assert free_optimum(m).length == pytest.approx(2 * math.hypot(0.5, 1.5))  # via a corner
    corners = {tuple(c) for c in obstacle_corners(b).tolist()}
    assert corners == {(1.0, 1.0), (2.0, 1.0), (1.0, 2.0), (2.0, 2.0)}
