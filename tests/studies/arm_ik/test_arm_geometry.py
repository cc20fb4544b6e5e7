"""Segment intersection edge cases, collision counting and the visibility distance."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.studies.arm_ik.geometry import (
    count_intersections,
    points_in_polygons,
    proper_crossings,
    segments_intersect,
)
from evomotion.studies.arm_ik.scenario import parse_scenario_text
from evomotion.studies.arm_ik.visibility import VisibilityGraph


def seg(x1, y1, x2, y2):
    return np.array([[x1, y1], [x2, y2]], dtype=float)


def inter(a, b, strict=False):
    return bool(segments_intersect(a, b, strict=strict))


def test_proper_crossing_and_disjoint():
    assert inter(seg(0, 0, 2, 2), seg(0, 2, 2, 0))
    assert not inter(seg(0, 0, 1, 1), seg(2, 0, 3, 1))
    assert not inter(seg(0, 0, 1, 0), seg(0, 1, 1, 1))  # parallel


def test_touching_endpoints_count_but_not_strictly():
    assert inter(seg(0, 0, 1, 1), seg(1, 1, 2, 0))  # shared endpoint
    assert inter(seg(0, 0, 2, 0), seg(1, 0, 1, 3))  # T-junction: endpoint on the interior
    assert not inter(seg(0, 0, 1, 1), seg(1, 1, 2, 0), strict=True)
    assert not inter(seg(0, 0, 2, 0), seg(1, 0, 1, 3), strict=True)


def test_collinear_cases():
    assert inter(seg(0, 0, 2, 0), seg(1, 0, 3, 0))  # overlapping
    assert inter(seg(0, 0, 1, 0), seg(1, 0, 3, 0))  # touching end to end
    assert not inter(seg(0, 0, 1, 0), seg(1.5, 0, 3, 0))  # collinear, apart
    assert inter(seg(0, 0, 4, 4), seg(1, 1, 2, 2))  # one contains the other
    assert not inter(seg(0, 0, 1, 1), seg(2, 2, 3, 3))
    assert not inter(seg(0, 0, 2, 0), seg(1, 0, 3, 0), strict=True)


def test_degenerate_point_segment():
    assert inter(seg(1, 0, 1, 0), seg(0, 0, 2, 0))
    assert not inter(seg(1, 1, 1, 1), seg(0, 0, 2, 0))


@settings(max_examples=200, deadline=None)
@given(st.lists(st.integers(-5, 5), min_size=8, max_size=8))
def test_symmetric_and_matches_bruteforce(c):
    a, b = seg(*c[:4]), seg(*c[4:])
    assert inter(a, b) == inter(b, a) == inter(a[::-1], b)
    # brute force on integer coordinates: sample points along a and test exact collinearity
    pts = [a[0] + (a[1] - a[0]) * t for t in np.linspace(0, 1, 241)]
    d = b[1] - b[0]
    on_b = []
    for p in pts:
        cross = d[0] * (p[1] - b[0][1]) - d[1] * (p[0] - b[0][0])
        inside = np.all(p >= np.minimum(*b) - 1e-9) and np.all(p <= np.maximum(*b) + 1e-9)
        on_b.append(abs(cross) < 1e-9 and inside)
    if any(on_b):  # a sampled point of a lies on b
        assert inter(a, b)
    if not inter(a, b):
        assert not any(on_b)


def test_count_intersections_batch_and_mask():
    obst = np.stack([seg(1, -1, 1, 1), seg(3, -1, 3, 1)])
    limbs = np.stack([
        np.stack([seg(0, 0, 2, 0), seg(2, 0, 4, 0)]),  # crosses both walls
        np.stack([seg(0, 0, 0.5, 0), seg(0.5, 0, 0.5, 0.5)]),  # none
    ])
    np.testing.assert_array_equal(count_intersections(limbs, obst), [2, 0])
    np.testing.assert_array_equal(count_intersections(limbs, obst, np.array([True, False])),
                                  [1, 0])
    assert count_intersections(limbs, np.zeros((0, 2, 2))).tolist() == [0, 0]


def test_points_in_polygons():
    sq = np.array([[0, 0], [2, 0], [2, 2], [0, 2], [0, 0]], dtype=float)
    inside = points_in_polygons(np.array([[1, 1], [3, 1], [1, -0.5]]), [sq])
    assert inside.tolist() == [True, False, False]


WALL = """10
10
1 5
1
9 5
1
1 0 360
1
1 0 360
1
2
5 2
5 8
"""


def test_visibility_distance_goes_around_the_wall():
    scn = parse_scenario_text(WALL)
    vg = VisibilityGraph.build(scn)
    d = vg.distances(np.array([[[1.0, 5.0]], [[9.0, 7.0]]]))  # (n=2, F=1, 2)
    around = np.hypot(4, 3) * 2  # via (5, 8) or (5, 2)
    assert np.isclose(d[0, 0, 0], around)
    assert np.isclose(d[1, 0, 0], 2.0)  # in plain sight
    closed = parse_scenario_text(WALL.replace("2\n5 2\n5 8\n",
                                              "5\n4 4\n6 4\n6 6\n4 6\n4 4\n"))
    d2 = VisibilityGraph.build(closed).distances(np.array([[[1.0, 5.0]]]))
    assert np.isclose(d2[0, 0, 0], np.hypot(3, 1) * 2 + 2)  # over the square's top side


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000), st.booleans())
def test_fast_count_matches_pairwise_test(seed, integer):
    rng = np.random.default_rng(seed)
    draw = (lambda *s: rng.integers(0, 4, s).astype(float)) if integer else \
        (lambda *s: rng.random(s) * 4)
    segs, obst = draw(6, 5, 2, 2), draw(7, 2, 2)
    slow = segments_intersect(segs[:, :, None], obst[None, None]).sum(axis=(1, 2))
    np.testing.assert_array_equal(count_intersections(segs, obst), slow)


def test_proper_crossings_equals_strict_test():
    rng = np.random.default_rng(4)
    p, q = rng.integers(0, 4, (300, 2, 2)).astype(float), rng.integers(0, 4, (300, 2, 2)) * 1.0
    np.testing.assert_array_equal(proper_crossings(p, q), segments_intersect(p, q, strict=True))
