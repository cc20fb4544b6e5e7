"""The walk generator: shapes, ranges, start-up, the loop of a cycle, the parts."""

import numpy as np
import pytest

from evomotion.sim.motion import format_motion, parse_motion
from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.joint_limits import JOINT_RANGES, check_hip_yaw_pitch
from evomotion.sim.robots.nao.leg_ik import leg_fk
from evomotion.studies.humanoid_walk import foot_gait
from evomotion.studies.humanoid_walk.walk_motion import assemble, walk_parts, whole_walk


def test_genes_bounds_and_default():
    assert len(foot_gait.NAMES) == len(set(foot_gait.NAMES)) == foot_gait.LOWER.size
    assert np.all(foot_gait.LOWER < foot_gait.UPPER)
    assert np.all((foot_gait.DEFAULT >= foot_gait.LOWER) & (foot_gait.DEFAULT <= foot_gait.UPPER))


def test_period_is_rounded_to_40_ms():
    assert foot_gait.period_ms(0.48) == 480
    assert foot_gait.period_ms(0.50) == 520 or foot_gait.period_ms(0.50) == 480
    assert np.all(foot_gait.period_ms(np.linspace(0.3, 0.7, 50)) % 40 == 0)


def test_schedule_covers_the_walk():
    s = foot_gait.schedule(0.48, 10.0, 1.0)
    assert s.steady_ms >= 10_000 and s.steady_ms % s.period_ms == 0
    assert s.steady_ms - s.period_ms < 10_000
    assert s.total_ms == s.ready_ms + 2 * s.ramp_ms + s.steady_ms + s.hold_ms


def test_targets_start_in_the_crouch_and_stay_in_range():
    rng = np.random.default_rng(0)
    span = foot_gait.UPPER - foot_gait.LOWER
    g = foot_gait.LOWER + span * rng.random((8, foot_gait.LOWER.size))
    g[:, foot_gait.INDEX["period_s"]] = 0.48
    s = foot_gait.schedule(0.48, 2.0, 0.5)
    q = foot_gait.joint_targets(g, foot_gait.key_times_ms(s), s)
    assert q.shape == (8, s.total_ms // foot_gait.POSE_MS + 1, len(nao.JOINTS))
    lo = np.array([JOINT_RANGES[j][0] for j in nao.JOINTS])
    hi = np.array([JOINT_RANGES[j][1] for j in nao.JOINTS])
    assert np.all((q >= lo) & (q <= hi))
    np.testing.assert_allclose(q[:, 0], np.clip(nao.pose_vector(), lo, hi)[None].repeat(8, 0))
    # one hip yaw-pitch motor
    np.testing.assert_array_equal(q[..., nao.JOINTS.index("LHipYawPitch")],
                                  q[..., nao.JOINTS.index("RHipYawPitch")])


def test_ready_pose_puts_the_ankles_where_the_genes_say():
    g = foot_gait.DEFAULT.copy()
    s = foot_gait.schedule(g[foot_gait.INDEX["period_s"]], 1.0, 0.0)
    q = foot_gait.joint_targets(g[None], np.array([s.ready_ms]), s)[0, 0]
    left = q[[nao.JOINTS.index(j) for j in nao.LEFT_LEG]]
    ankle, _ = leg_fk(left, left=True)
    lean = g[foot_gait.INDEX["lean_rad"]]
    c, sn = np.cos(lean), np.sin(lean)
    walk = np.array([c * ankle[0] + sn * ankle[2], ankle[1], -sn * ankle[0] + c * ankle[2]])
    want = [g[foot_gait.INDEX["x_offset_m"]], nao.HIP_OFFSET_Y_M + g[foot_gait.INDEX["width_m"]],
            -(nao.HIP_OFFSET_Z_M + g[foot_gait.INDEX["leg_height_m"]])]
    # lateral sway is at its extreme at the ready instant (amplitude 0 there)
    np.testing.assert_allclose(walk, want, atol=2e-3)


def test_parts_loop_and_assemble_into_the_whole_walk():
    parts = walk_parts(foot_gait.DEFAULT, 3.0)
    c = parts.cycle.values
    np.testing.assert_array_equal(c[0], c[-1])
    np.testing.assert_array_equal(parts.start.values[-1], c[0])
    np.testing.assert_array_equal(parts.stop.values[0], c[0])
    whole = assemble(parts)
    assert whole.duration_s == pytest.approx(parts.start.duration_s + parts.cycles
                                             * parts.cycle.duration_s + parts.stop.duration_s)
    k = len(parts.start.times_ms) - 1
    n = len(c) - 1
    for i in range(parts.cycles):
        np.testing.assert_array_equal(whole.values[k + i * n:k + (i + 1) * n + 1], c)
    # the steady cycles are the generator's own poses (periodic to rounding)
    s = parts.schedule
    t = np.arange(0, s.walk_end_ms + 1, foot_gait.POSE_MS)
    direct = foot_gait.joint_targets(foot_gait.DEFAULT[None], t, s)[0]
    np.testing.assert_allclose(whole.values, direct, atol=1e-9)
    check_hip_yaw_pitch(whole)


def test_whole_walk_round_trips_through_the_motion_format():
    m = whole_walk(foot_gait.DEFAULT, 1.0)
    back = parse_motion(format_motion(m))
    np.testing.assert_array_equal(back.values, m.values)
    np.testing.assert_array_equal(back.times_ms, m.times_ms)


def test_named_genes():
    d = foot_gait.named(foot_gait.DEFAULT)
    assert set(foot_gait.NAMES) <= set(d) and d["period_used_s"] == 0.56
