"""The kick that follows the ball and the left-foot kick (the right one in mirror image):
on the shipped kick, a ball 1.5 cm right of its place turns the blind kick far off its aim but
not the adaptive one; a ball where the kick wants it kicks exactly as before; the left-foot
kick at +a is the right-foot kick at -a in mirror image; another robot's kicker refuses it."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.studies.biped_kick.experiment import perturbed_kicks
from evomotion.studies.biped_kick.play import read_kick
from evomotion.studies.biped_kick.problem import KickConfig, KickProblem


@pytest.fixture(scope="module")
def kick():
    genome, _ = read_kick(None)
    return KickProblem(KickConfig(nthread=2)), genome


def test_the_adaptive_kick_follows_the_ball(kick):
    p, g = kick
    offsets = np.array([[0.0, 0.0], [0.0, -0.015], [0.01, -0.01]])
    blind = perturbed_kicks(p, g, offsets)
    seen = perturbed_kicks(p, g, offsets, adapt=True)
    # the ball where the kick wants it: the same kick, bit for bit
    assert seen["distance_m"][0] == blind["distance_m"][0]
    assert seen["angle_error_deg"][0] == blind["angle_error_deg"][0]
    assert np.abs(blind["angle_error_deg"][1:]).min() > 5.0
    assert np.abs(seen["angle_error_deg"]).max() < 2.0 and not seen["fell"].any()
    assert seen["distance_m"].min() > 2.5


def test_the_left_foot_kick_is_the_right_one_in_mirror_image(kick):
    p, g = kick
    offsets = np.array([[0.005, 0.01]])
    right = p.kicks(g[None], np.radians([-20.0]), p.ball_xy(g[None], np.radians([-20.0]))
                    + offsets)
    flip = np.array([1.0, -1.0])
    ball = (p.ball_xy(g[None], np.radians([-20.0])) + offsets) * flip
    left = p.kicks(g[None], np.radians([20.0]), ball, left_foot=True)
    assert np.allclose(left["travel"], right["travel"] * flip, atol=1e-3)
    assert abs(np.degrees(left["angle_error_rad"][0]) + np.degrees(
        right["angle_error_rad"][0])) < 0.1 and not left["fell"].any()
    # the experiment helper places the ball for the left foot the same way
    same = perturbed_kicks(p, g, offsets * flip, 20.0, left_foot=True)
    assert np.isclose(same["angle_error_deg"][0], np.degrees(left["angle_error_rad"][0]))


def test_another_robots_kicker_has_no_left_foot():
    p = KickProblem(KickConfig(robot="op3", nthread=1, aims_deg=(0.0,)))
    g = p.initial_population(1, np.random.default_rng(0))[0]
    with pytest.raises(InputError, match="left-foot kick") as e:
        p.kicks(g[None], np.zeros(1), p.ball_xy(g[None], np.zeros(1)), left_foot=True)
    assert "\n" not in str(e.value)
