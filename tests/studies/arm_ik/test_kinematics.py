"""Forward kinematics against hand-computed chains; layout and heuristics."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.studies.arm_ik.heuristics import build_wrist_map
from evomotion.studies.arm_ik.kinematics import Layout, forward
from evomotion.studies.arm_ik.scenario import load_scenario, parse_scenario_text

TWO_FINGERS = """10
10
5 5
2
1 1
9 9
2
2 0 360
1 0 360
1
1 0 360
2
1 0 360
1 0 90
0
"""


def test_forward_hand_computed():
    scn = parse_scenario_text(TWO_FINGERS)
    lay = Layout.of(scn)
    assert lay.dim == 5 and lay.finger_bones == (1, 2)
    # arm: 90 deg (up), then +90 (left); finger 1: +90 (down); finger 2: 0 (left), then -> 90
    g = np.array([[90, 90, 90, 0, 90]], dtype=float)
    p = forward(scn, lay, g)
    np.testing.assert_allclose(p.arm_joints[0], [[5, 5], [5, 7], [4, 7]], atol=1e-12)
    np.testing.assert_allclose(p.wrist[0], [4, 7], atol=1e-12)
    np.testing.assert_allclose(p.finger_joints[0, 0, :2], [[4, 7], [4, 6]], atol=1e-12)
    np.testing.assert_allclose(p.finger_joints[0, 1], [[4, 7], [3, 7], [3, 6]], atol=1e-12)
    np.testing.assert_allclose(p.tips[0], [[4, 6], [3, 6]], atol=1e-12)
    # padded bone repeats the tip and is masked out of the collision segments
    np.testing.assert_allclose(p.finger_joints[0, 0, 2], [4, 6], atol=1e-12)
    assert lay.finger_mask.tolist() == [[True, False], [True, True]]
    arm, fingers = lay.split(g[0])
    assert arm == [90, 90] and fingers == [[90], [0, 90]]


def test_forward_straight_and_batch_independent():
    scn = parse_scenario_text(TWO_FINGERS)
    lay = Layout.of(scn)
    g = np.zeros((3, lay.dim))
    g[1] = [45, 315, 30, 60, 270]
    p = forward(scn, lay, g)
    np.testing.assert_allclose(p.wrist[0], [8, 5])  # straight along +x
    np.testing.assert_allclose(p.tips[0], [[9, 5], [10, 5]])
    a, b = np.deg2rad(45), 0.0  # second bone: 45 + 315 = 360 -> +x
    wrist = np.array([5 + 2 * np.cos(a) + np.cos(b), 5 + 2 * np.sin(a)])
    np.testing.assert_allclose(p.wrist[1], wrist)
    np.testing.assert_allclose(forward(scn, lay, g[1:2]).tips[0], p.tips[1])
    # bone lengths are preserved
    seg = p.arm_segments()
    np.testing.assert_allclose(np.linalg.norm(seg[:, :, 1] - seg[:, :, 0], axis=-1),
                               np.broadcast_to([2.0, 1.0], (3, 2)))


def test_layout_bounds_and_keys():
    scn = parse_scenario_text(TWO_FINGERS)
    lay = Layout.of(scn, with_keys=True)
    assert lay.dim == 7 and lay.keys == slice(5, 7)
    np.testing.assert_array_equal(lay.lower, [0, 0, 0, 0, 0, 0, 0])
    np.testing.assert_array_equal(lay.upper, [360, 360, 360, 360, 90, 1, 1])
    assert lay.full_circle.tolist() == [True, True, True, True, False, False, False]


def test_wrist_map_marks_closed_obstacle_unreachable_and_candidates():
    scn = load_scenario("paper_example")
    wm = build_wrist_map(scn, cell=0.1)
    c = wm.centres()
    inside_diamond = np.abs(c[..., 0] - 3) + np.abs(c[..., 1] - 1) < 0.8
    assert not wm.reachable[inside_diamond].any()
    assert wm.reachable.mean() > 0.9
    assert wm.candidate.any() and not (wm.candidate & ~wm.reachable).any()
    # every candidate centre is within the arm's reach of the start (+ half a cell)
    d = np.linalg.norm(c[wm.candidate] - scn.start, axis=-1)
    assert d.min() >= 2 - 0.08 and d.max() <= 4 + 0.08
    assert np.all(wm.wrist_distance(c[wm.candidate]) == 0)
    assert wm.wrist_distance(np.array([[-1.0, -1.0]]))[0] > 1.0
    none = build_wrist_map(load_scenario("unreachable"), cell=0.2)
    assert not none.candidate.any() and np.all(np.isfinite(none.wrist_distance(c[0])))


BOXED = """10
10
5 5
1
5 6
1
1 0 360
1
1 0 360
1
5
3 3
7 3
7 7
3 7
3 3
"""


def test_reachable_cells_stay_inside_a_closed_box():
    wm = build_wrist_map(parse_scenario_text(BOXED), cell=0.25)
    c = wm.centres()
    inside = (c[..., 0] > 3) & (c[..., 0] < 7) & (c[..., 1] > 3) & (c[..., 1] < 7)
    np.testing.assert_array_equal(wm.reachable, inside)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(0, 360), min_size=6, max_size=6))
def test_fk_bone_lengths_and_reach(angles):
    scn = load_scenario("paper_example")
    lay = Layout.of(scn)
    p = forward(scn, lay, np.array([angles]))
    bones = np.linalg.norm(np.diff(p.arm_joints[0], axis=0), axis=1)
    np.testing.assert_allclose(bones, scn.arm.length)
    lo, hi = scn.arm.reach()
    assert lo - 1e-9 <= np.linalg.norm(p.wrist[0] - scn.start) <= hi + 1e-9
    for j, f in enumerate(scn.fingers):
        d = np.linalg.norm(p.tips[0, j] - p.wrist[0])
        assert f.reach()[0] - 1e-9 <= d <= f.reach()[1] + 1e-9
