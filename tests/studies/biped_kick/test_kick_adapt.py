"""The kick that follows the ball within the robot's limits and the left-foot kick (the right
one in mirror image): a ball in its place kicks exactly as before; an offset ball is followed
as far as the joint ranges and motor speeds allow, never beyond, and the kick goes nearer its
aim than the blind one; the left-foot kick at +a is the right-foot kick at -a in mirror image;
bad flags and another robot's kicker are one line."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.studies.biped_kick.adaptive import (
    FRACTIONS,
    SWING,
    reachable_shift,
    retimed,
    rolled_in_air,
)
from evomotion.studies.biped_kick.experiment import accuracy, perturbed_kicks
from evomotion.studies.biped_kick.motion import (
    GENE_INDEX,
    GENES,
    SETTLE_S,
    START,
    execution_time_s,
    gene,
    key_times,
)
from evomotion.studies.biped_kick.play import read_kick
from evomotion.studies.biped_kick.problem import KickConfig, KickProblem


@pytest.fixture(scope="module")
def kick():
    genome, _ = read_kick(None)
    return KickProblem(KickConfig(nthread=2)), genome


def test_the_adaptive_kick_follows_the_ball_within_the_limits(kick):
    """With the sole kept level (``adapt_foot_roll_rad`` 0) the outboard balls are followed in
    part: the kicking ankle's roll reaches its range."""
    p, g = kick
    p = KickProblem(dataclasses.replace(p.cfg, adapt_foot_roll_rad=0.0))
    offsets = np.array([[0.0, 0.0], [0.0, -0.015], [0.01, -0.01], [0.0, 0.01]])
    blind = perturbed_kicks(p, g, offsets)
    seen = perturbed_kicks(p, g, offsets, adapt=True)
    # the ball where the kick wants it: the same kick, bit for bit
    assert seen["adapt_fraction"][0] == 1.0
    assert seen["distance_m"][0] == blind["distance_m"][0]
    assert seen["angle_error_deg"][0] == blind["angle_error_deg"][0]
    # never beyond a joint's range or a motor's speed; the outboard balls followed in part
    assert not seen["range_excess_rad"].any() and not seen["speed_excess_s"].any()
    assert 0 < seen["adapt_fraction"][1] < 1 and 0 < seen["adapt_fraction"][2] < 1
    assert np.all(np.abs(seen["angle_error_deg"][1:3]) < np.abs(blind["angle_error_deg"][1:3])
                  - 4.0)
    assert not seen["fell"].any()
    assert accuracy(seen)["over_limits"] == 0.0


def test_the_foot_rolled_in_the_air_follows_an_outboard_ball_whole(kick):
    """Balls 1.5-2 cm outboard of the kicking foot, which a level sole follows only in part (its
    ankle roll at its range: 0.1-0.2 of the offset, over 10 deg off the aim), are followed
    wholly or nearly (0.8 of 2 cm outboard and 1 cm ahead) when the foot may roll 0.1 rad in
    the air, within 6 deg of the aim: every played pose within every joint's range and motor's
    speed, the sole rolled by at most 0.1 rad and only while the foot is off the ground; a ball
    in its place kicks bit for bit as with the level sole."""
    p, g = kick
    level = KickProblem(dataclasses.replace(p.cfg, adapt_foot_roll_rad=0.0))
    off = np.array([[0.0, -0.015], [0.01, -0.02], [0.0, 0.0]])
    a = -20.0
    rolled, flat = (perturbed_kicks(q, g, off, a, adapt=True) for q in (p, level))
    assert np.all(flat["adapt_fraction"][:2] < 0.5)
    assert rolled["adapt_fraction"][0] == rolled["adapt_fraction"][2] == 1.0
    assert rolled["adapt_fraction"][1] >= 0.8
    assert not rolled["range_excess_rad"].any() and not rolled["speed_excess_s"].any()
    assert np.all(np.abs(rolled["angle_error_deg"][:2]) < 6.0)
    assert np.all(np.abs(flat["angle_error_deg"][:2]) > 10.0) and not rolled["fell"].any()
    assert rolled["distance_m"][2] == flat["distance_m"][2]
    assert rolled["angle_error_deg"][2] == flat["angle_error_deg"][2]
    # the played poses: only the kicking ankle's roll differs from the level sole's, by at
    # most 0.1 rad, and only between the lift's start and the retract's end
    gg = np.repeat(g[None], 2, 0)
    aims = np.radians([a, a])
    shift = p.ball_xy(gg, aims) + off[:2] - p.wanted_ball_xy(gg, aims)
    keys_r = p.controls(gg, aims, shift)[0]
    keys_l = level.controls(gg, aims, shift)[0]
    col = p.kicker.swing_roll[0]
    diff = np.abs(keys_r - keys_l)
    assert np.all(np.delete(diff, col, axis=2) == 0.0) and 0.0 < diff[..., col].max() <= 0.1
    t = key_times(gg) - SETTLE_S
    lift = gene(gg, "t_shift_s")[:, None]
    down = lift + sum(gene(gg, n)[:, None] for n in SWING)
    assert np.all(diff[..., col][(t <= lift) | (t >= down)] == 0.0)


def test_the_left_foot_rolls_within_its_own_range(kick):
    """The clip range is inside the right ankle's range and, in mirror image, the left
    ankle's: a left-foot kick at +20 deg of a ball 1.5 cm outboard (to its left) is followed
    wholly (the level sole: in part) within every range, as the right foot's at -20 deg."""
    from evomotion.sim.robots.nao.joint_limits import JOINT_RANGES

    p, g = kick
    col, lo, hi = p.kicker.swing_roll
    (rlo, rhi), (llo, lhi) = JOINT_RANGES["RAnkleRoll"], JOINT_RANGES["LAnkleRoll"]
    assert rlo <= lo < hi <= rhi and llo <= -hi < -lo <= lhi
    level = KickProblem(dataclasses.replace(p.cfg, adapt_foot_roll_rad=0.0))
    off = np.array([[0.0, 0.015], [0.0, 0.0]])
    rolled, flat = (perturbed_kicks(q, g, off, 20.0, adapt=True, left_foot=True)
                    for q in (p, level))
    assert flat["adapt_fraction"][0] < 0.5 and rolled["adapt_fraction"][0] == 1.0
    assert not rolled["range_excess_rad"].any() and not rolled["speed_excess_s"].any()
    assert abs(rolled["angle_error_deg"][0]) < 6.0 < abs(flat["angle_error_deg"][0])
    assert rolled["distance_m"][1] == flat["distance_m"][1] and not rolled["fell"].any()


def test_rolled_in_air_clips_only_within_its_allowance():
    """A synthetic roll 0.05 and 0.3 rad beyond its range in the air and 0.05 on the ground:
    only the first is clipped (allowance 0.1); an allowance of 0, or no swing roll, changes
    nothing."""
    g = np.array([[START[n] for n, *_ in GENES]])
    t = key_times(g)
    tt = t - SETTLE_S
    lift = gene(g, "t_shift_s")[0]
    down = lift + sum(gene(g, n)[0] for n in SWING)
    air = (tt > lift) & (tt < down)
    keys = np.zeros((1, len(t), 22))
    col = 3
    i_air, j_air = np.nonzero(air)[0][[1, 3]]
    i_ground = np.nonzero(~air)[0][0]
    keys[0, i_air, col], keys[0, j_air, col] = 0.45, 0.7
    keys[0, i_ground, col] = -0.45
    out = rolled_in_air(keys.copy(), g, t, (col, -0.4, 0.4), 0.1)
    assert out[0, i_air, col] == 0.4 and out[0, j_air, col] == 0.7
    assert out[0, i_ground, col] == -0.45
    assert np.array_equal(np.delete(out, col, axis=2), np.delete(keys, col, axis=2))
    assert np.array_equal(rolled_in_air(keys.copy(), g, t, (col, -0.4, 0.4), 0.0), keys)
    assert np.array_equal(rolled_in_air(keys.copy(), g, t, None, 0.1), keys)
    for bad in (-0.1, 0.6, float("nan")):
        with pytest.raises(InputError, match="problem.adapt_foot_roll_rad") as e:
            KickConfig(adapt_foot_roll_rad=bad).validate()
        assert "\n" not in str(e.value)


def test_reachable_shift_takes_the_largest_fraction_within_the_limits():
    """A fake kick whose ankle leaves its range (0.5 rad) beyond 1 cm of shift: each kick gets
    the largest tried fraction (tenths) of its shift within 1 cm, at its own timing."""
    def keys_of(rows, s, stretch):
        q = np.zeros((len(rows), 3, 22))
        q[:, 1, 0] = 0.5 * np.hypot(s[:, 0], s[:, 1]) / 0.01  # joint 0: range +-0.5 rad
        return q

    lim = (np.full(22, -0.5), np.full(22, 0.5), np.full(22, 1e9))
    shift = np.array([[0.005, 0.0], [0.02, 0.0], [0.0, -0.04]])
    for most in (1.0, 1.25):  # a joint out of range: no stretch helps
        used, frac, stretch = reachable_shift(keys_of, shift, 1.0, lim, most)
        assert np.allclose(frac, [1.0, 0.5, 0.2]) and np.allclose(used, shift * frac[:, None])
        assert np.all(stretch == 1.0)
    assert FRACTIONS == 10


def test_a_swing_too_fast_for_its_motor_is_slowed_down_not_cut():
    """A fake kick whose joint 0 turns 0.5 rad per 20 ms per cm of shift, divided by the
    stretch, its motor 25 rad/s (0.5 rad per 20 ms): 1.2 cm needs the swing 1.2x longer; the
    evolved timing alone (max_stretch 1) takes 0.8 of it; 2 cm needs 2x, more than 1.25 allows,
    so it is cut to the largest fraction that 1.25 reaches (0.6: 1.2x)."""
    def keys_of(rows, s, stretch):
        q = np.zeros((len(rows), 3, 22))
        q[:, 1, 0] = 0.5 * np.hypot(s[:, 0], s[:, 1]) / 0.01 / stretch
        return q

    lim = (np.full(22, -10.0), np.full(22, 10.0), np.full(22, 25.0))
    shift = np.array([[0.012, 0.0], [0.02, 0.0], [0.005, 0.0]])
    _, frac, stretch = reachable_shift(keys_of, shift, 1.0, lim, 1.0)
    assert np.allclose(frac, [0.8, 0.5, 1.0]) and np.all(stretch == 1.0)
    _, frac, stretch = reachable_shift(keys_of, shift, 1.0, lim, 1.25)
    assert np.allclose(frac, [1.0, 0.6, 1.0])
    assert 1.2 <= stretch[0] <= 1.21 and 1.2 <= stretch[1] <= 1.21 and stretch[2] == 1.0
    # a kick too fast even at no fraction (joint 1 at 1.1x its motor's speed whatever the
    # shift) is slowed down, never played too fast; with max_stretch 1 it keeps lambda = 0
    # and its own timing (the kick as evolved)
    def too_fast(rows, s, stretch):
        q = keys_of(rows, s, stretch)
        q[:, 1, 1] = 0.55 / stretch
        return q

    used, frac, stretch = reachable_shift(too_fast, shift, 1.0, lim, 1.25)
    assert np.allclose(frac, [1.0, 0.6, 1.0]) and np.all(stretch >= 1.1)
    _, frac, stretch = reachable_shift(too_fast, np.array([[0.2, 0.0]]), 1.0, lim, 1.25)
    assert frac[0] == 0.0 and 1.1 <= stretch[0] <= 1.25  # lambda = 0, slowed down
    _, frac, stretch = reachable_shift(too_fast, shift, 1.0, lim, 1.0)
    assert np.all(frac == 0.0) and np.all(stretch == 1.0)
    # a stretch needed just under the cap is found (the last try is at the cap itself)
    _, frac, stretch = reachable_shift(too_fast, np.zeros((1, 2)), 1.0, lim, 1.1005)
    assert frac[0] == 1.0 and 1.1 <= stretch[0] <= 1.1005
    g = np.tile(np.arange(1.0, len(GENES) + 1), (2, 1))
    out = retimed(g, np.array([1.0, 1.5]))
    assert np.array_equal(out[0], g[0])
    swing = [GENE_INDEX[name] for name in SWING]
    assert np.allclose(out[1, swing], 1.5 * g[1, swing])
    assert np.array_equal(np.delete(out[1], swing), np.delete(g[1], swing))


def test_the_following_kick_slows_its_swing_where_its_motors_need_it(kick):
    """The shipped kick runs its kicking hip at 0.99 of the motor's speed at 30 deg: commanded
    at 36 deg it is within the speeds only slowed down, and it is (no excess); with
    adapt_max_stretch 1 it keeps its evolved timing and, too fast there, falls back to the
    kick as evolved; a ball in its place at 0 deg needs no stretch (the kick bit for bit)."""
    p, g = kick
    evolved = KickProblem(dataclasses.replace(p.cfg, adapt_max_stretch=1.0))
    a = np.radians([36.0, 0.0])
    gg = np.repeat(g[None], 2, 0)
    ball = p.wanted_ball_xy(gg, a)
    k = p.kicks(gg, a, ball, adapt=True)
    assert 1.0 < k["stretch"][0] <= 1.25 and k["stretch"][1] == 1.0
    assert not k["range_excess_rad"].any() and not k["speed_excess_s"].any()
    assert k["exec_time_s"][0] > execution_time_s(g[None])[0]
    k1 = evolved.kicks(gg, a, ball, adapt=True)
    assert np.all(k1["stretch"] == 1.0) and k1["speed_excess_s"][0] > 0
    assert k["travel"][1].tolist() == k1["travel"][1].tolist()
    blind = p.kicks(gg[1:], a[1:], ball[1:])
    assert k["travel"][1].tolist() == blind["travel"][0].tolist()
    for bad in (0.9, 2.5, float("nan")):
        with pytest.raises(InputError, match="problem.adapt_max_stretch") as e:
            KickConfig(adapt_max_stretch=bad).validate()
        assert "\n" not in str(e.value)


def test_the_left_foot_kick_is_the_right_one_in_mirror_image(kick):
    p, g = kick
    offsets = np.array([[0.005, 0.01]])
    a = np.radians([-20.0])
    right = p.kicks(g[None], a, p.ball_xy(g[None], a) + offsets)
    flip = np.array([1.0, -1.0])
    left = p.kicks(g[None], -a, (p.ball_xy(g[None], a) + offsets) * flip, left_foot=True)
    assert np.allclose(left["travel"], right["travel"] * flip, atol=1e-3)
    assert abs(np.degrees(left["angle_error_rad"][0]) + np.degrees(
        right["angle_error_rad"][0])) < 0.1 and not left["fell"].any()
    # the experiment helper places the ball for the left foot the same way
    same = perturbed_kicks(p, g, offsets * flip, 20.0, left_foot=True)
    assert np.isclose(same["angle_error_deg"][0], np.degrees(left["angle_error_rad"][0]))


@pytest.mark.parametrize("flag", ["no", [True, False, True], 1])
def test_bad_left_foot_flags_are_one_line(kick, flag):
    p, g = kick
    with pytest.raises(InputError, match="left-foot kick") as e:
        p.kicks(np.repeat(g[None], 2, 0), np.zeros(2), p.ball_xy(g[None], np.zeros(1)).repeat(
            2, 0), left_foot=flag)
    assert "\n" not in str(e.value)
    with pytest.raises(InputError, match="left_foot"):
        perturbed_kicks(p, g, np.zeros((1, 2)), left_foot="yes")
    with pytest.raises(InputError, match=r"\[n, 2\]"):
        perturbed_kicks(p, g, np.zeros(3))


def test_another_robots_kicker_has_no_left_foot():
    p = KickProblem(KickConfig(robot="op3", nthread=1, aims_deg=(0.0,)))
    g = p.initial_population(1, np.random.default_rng(0))[0]
    with pytest.raises(InputError, match="left-foot kick") as e:
        p.kicks(g[None], np.zeros(1), p.ball_xy(g[None], np.zeros(1)), left_foot=True)
    assert "\n" not in str(e.value)
