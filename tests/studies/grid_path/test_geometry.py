"""Exact segment validity against the brute-force rational reference."""

from __future__ import annotations

import numpy as np
import pytest
from gp_reference import valid_reference
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.studies.grid_path.geometry import points_free, segments_valid


@st.composite
def map_and_segments(draw):
    w, h = draw(st.integers(2, 7)), draw(st.integers(2, 7))
    cells = draw(st.lists(st.booleans(), min_size=w * h, max_size=w * h))
    blocked = np.array(cells, dtype=bool).reshape(h, w)
    q = draw(st.sampled_from([1, 2, 4, 8]))  # endpoint lattice: corners, centres, finer
    coord = st.tuples(st.integers(-q // 2, w * q + q // 2), st.integers(-q // 2, h * q + q // 2))
    segs = draw(st.lists(st.tuples(coord, coord), min_size=1, max_size=12))
    p0 = np.array([s[0] for s in segs], float) / q
    p1 = np.array([s[1] for s in segs], float) / q
    return blocked, p0, p1


@settings(max_examples=150, deadline=None)
@given(map_and_segments(), st.sampled_from(["open", "closed"]))
def test_segments_valid_matches_bruteforce_reference(data, rule):
    blocked, p0, p1 = data
    got = segments_valid(blocked, p0, p1, rule)
    want = [valid_reference(blocked, a, b, rule) for a, b in zip(p0, p1, strict=True)]
    assert got.tolist() == want


def test_large_mixed_batch_grouped_by_length():
    rng = np.random.default_rng(5)
    blocked = rng.random((8, 8)) < 0.3
    p0 = rng.integers(0, 17, (120, 2)) / 2.0
    p1 = np.where(rng.random((120, 1)) < 0.7, p0 + rng.integers(-2, 3, (120, 2)) / 2.0,
                  rng.integers(0, 17, (120, 2)) / 2.0)  # mostly short, some long
    got = segments_valid(blocked, p0, p1, "open")
    want = [valid_reference(blocked, a, b, "open") for a, b in zip(p0, p1, strict=True)]
    assert got.tolist() == want


def test_corner_and_edge_cases():
    b = np.zeros((3, 3), bool)
    b[0, 1] = True  # cell x=1, y=0
    p0 = np.array([[0.5, 0.5], [0.5, 0.5], [0.5, 1.5], [0, 1], [1, 0], [0.5, 0.5]])
    p1 = np.array([[1.5, 1.5], [2.5, 0.5], [2.5, 1.5], [3, 1], [2, 1], [0.5, 0.5]])
    # diagonal past the corner / through the block / row above / along its top edge /
    # its own diagonal (interior) / a point
    assert segments_valid(b, p0, p1, "open").tolist() == [True, False, True, True, False, True]
    assert segments_valid(b, p0, p1, "closed").tolist() == [False, False, True, False, False,
                                                            True]


def test_pinch_point_between_diagonal_blocks_is_open_only():
    b = np.array([[1, 0], [0, 1]], bool)  # (0,0) and (1,1) blocked, touching at (1,1)
    p0, p1 = np.array([[0.0, 2.0]]), np.array([[2.0, 0.0]])
    assert segments_valid(b, p0, p1, "open")[0]
    assert not segments_valid(b, p0, p1, "closed")[0]


def test_edge_shared_by_two_blocked_cells_is_interior():
    b = np.zeros((3, 3), bool)
    b[1, 0] = b[1, 1] = True  # a wall x in [0, 2], y in [1, 2]
    assert not segments_valid(b, [[1.0, 0.5]], [[1.0, 2.5]], "open")[0]  # through the wall
    assert segments_valid(b, [[0.0, 1.0]], [[2.0, 1.0]], "open")[0]  # along its bottom
    assert segments_valid(b, [[0.5, 2.0]], [[0.5, 3.0]], "open")[0]  # touches its top
    # along the map border above a blocked border cell: interior of obstacle + outside
    assert not segments_valid(b, [[0.0, 1.2]], [[0.0, 1.8]], "open")[0]


def test_outside_the_map_is_blocked_and_points():
    b = np.zeros((2, 2), bool)
    assert not segments_valid(b, [[0.5, 0.5]], [[-0.5, 0.5]], "open")[0]
    assert segments_valid(b, [[0.0, 0.0]], [[0.0, 2.0]], "open")[0]  # along the border
    assert not segments_valid(b, [[0.0, 0.0]], [[0.0, 2.0]], "closed")[0]
    assert points_free(b, [[0.5, 0.5], [3.0, 0.5]]).tolist() == [True, False]
    with pytest.raises(ValueError, match="unknown validity rule"):
        segments_valid(b, [[0, 0]], [[1, 1]], "touch")
