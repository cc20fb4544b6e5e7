"""The kick that follows the ball within the robot's limits and the left-foot kick (the right
one in mirror image): a ball in its place kicks exactly as before; an offset ball is followed
as far as the joint ranges and motor speeds allow, never beyond, and the kick goes nearer its
aim than the blind one; the left-foot kick at +a is the right-foot kick at -a in mirror image;
bad flags and another robot's kicker are one line."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.studies.biped_kick.adaptive import FRACTIONS, reachable_shift
from evomotion.studies.biped_kick.experiment import accuracy, perturbed_kicks
from evomotion.studies.biped_kick.play import read_kick
from evomotion.studies.biped_kick.problem import KickConfig, KickProblem


@pytest.fixture(scope="module")
def kick():
    genome, _ = read_kick(None)
    return KickProblem(KickConfig(nthread=2)), genome


def test_the_adaptive_kick_follows_the_ball_within_the_limits(kick):
    p, g = kick
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


def test_reachable_shift_takes_the_largest_fraction_within_the_limits():
    """A fake kick whose ankle leaves its range (0.5 rad) beyond 1 cm of shift: each kick gets
    the largest tried fraction (tenths) of its shift within 1 cm."""
    def keys_of(rows, s):
        q = np.zeros((len(rows), 3, 22))
        q[:, 1, 0] = 0.5 * np.hypot(s[:, 0], s[:, 1]) / 0.01  # joint 0: range +-0.5 rad
        return q

    lim = (np.full(22, -0.5), np.full(22, 0.5), np.full(22, 1e9))
    shift = np.array([[0.005, 0.0], [0.02, 0.0], [0.0, -0.04]])
    used, frac = reachable_shift(keys_of, shift, 1.0, lim)
    assert np.allclose(frac, [1.0, 0.5, 0.2]) and np.allclose(used, shift * frac[:, None])
    assert FRACTIONS == 10


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
