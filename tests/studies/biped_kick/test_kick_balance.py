"""Balance feedback during the kick (studies/biped_kick/balance.py, the ``feedback`` of
sim/worlds.simulate_worlds): the support ankle reads the gyro, targets reach the servos after
each world's latency, zero gains keep the open-loop kick, bad settings are one line."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.sim.state import state_qvel
from evomotion.sim.worlds import simulate_worlds
from evomotion.studies.biped_kick.balance import BalanceFeedback
from evomotion.studies.biped_kick.experiment import kick_worlds
from evomotion.studies.biped_kick.play import read_kick
from evomotion.studies.biped_kick.problem import KickConfig, KickProblem

NSTEP = 90


@pytest.fixture(scope="module")
def scene():
    """The kick problem, three perturbed worlds (latencies differ), the first NSTEP steps of
    the shipped kick and its start."""
    p = KickProblem(KickConfig(nthread=1))
    g = np.tile(read_kick(None)[0], (3, 1))
    aims = np.zeros(3)
    ctrl = p.controls(g, aims)[1][:, :NSTEP]
    s0 = np.stack([p.kicker.initial_state(b) for b in p.ball_xy(g, aims)])
    worlds = kick_worlds(p, 3, np.random.default_rng(7))
    assert len({w.latency_steps for w in worlds}) > 1
    return p, worlds, ctrl, s0


def _segmented(worlds, s0, ctrl):
    return simulate_worlds(worlds, s0, ctrl, 1, stopped=lambda s: np.zeros(len(s), bool),
                           segment_steps=3)


def test_a_constant_feedback_is_the_delayed_open_loop_bit_for_bit(scene):
    """Feedback 0 is the open loop stepped in control periods; a constant offset c reaches the
    servos as the open loop of controls + c, delayed by each world's latency alike."""
    p, worlds, ctrl, s0 = scene
    nu = p.model.nu
    zero = simulate_worlds(worlds, s0, ctrl, 1, feedback=lambda r, t, s: np.zeros((len(r), nu)),
                           control_steps=3)
    assert np.array_equal(zero, _segmented(worlds, s0, ctrl))
    c = np.zeros(nu)
    c[p.model.actuator("LAnklePitch").id] = 0.05
    starts = []

    def constant(rows, start, states):
        starts.append(start)
        return np.tile(c, (len(rows), 1))

    got = simulate_worlds(worlds, s0, ctrl, 1, feedback=constant, control_steps=3)
    assert starts == list(range(0, NSTEP, 3))
    assert np.array_equal(got, _segmented(worlds, s0, ctrl + c))
    assert not np.array_equal(got, zero)


def test_the_support_ankle_reads_the_gyro(scene):
    """Equation (1): the left ankle for a right-foot kick, the right one for a left-foot kick;
    nothing else moves."""
    p, _, _, s0 = scene
    m = p.model
    states = np.array(s0[:2])
    omega = state_qvel(m, states, "root", 6)
    omega[:, 3:6] = [[0.3, -0.2, 0.1], [-0.4, 0.5, 0.0]]
    fb = BalanceFeedback(m, (0.05, 0.02), np.array([False, True]))
    out = fb(np.arange(2), 0, states)
    want = np.zeros((2, m.nu))
    want[0, m.actuator("LAnklePitch").id], want[0, m.actuator("LAnkleRoll").id] = -0.01, 0.006
    want[1, m.actuator("RAnklePitch").id], want[1, m.actuator("RAnkleRoll").id] = 0.025, -0.008
    np.testing.assert_allclose(out, want, atol=1e-15)


def test_zero_gains_keep_the_open_loop_kick_and_gains_close_it(scene):
    p, *_ = scene
    assert not p.closed_loop
    g = np.tile(read_kick(None)[0], (2, 1))
    aims = np.zeros(2)
    fb = KickProblem(KickConfig(nthread=1, balance_gains=(0.05, 0.0)))
    assert fb.closed_loop and fb.control_steps == 3
    a = p.kicks(g, aims, p.ball_xy(g, aims))
    b = fb.kicks(g, aims, fb.ball_xy(g, aims))
    assert not np.array_equal(a["travel"], b["travel"])  # the feedback acted
    assert np.array_equal(b["travel"][0], b["travel"][1])  # rows stay independent
    assert not b["fell"].any()


@pytest.mark.parametrize("cfg,match", [
    ({"balance_gains": (0.1,)}, "problem.balance_gains: expected two gains"),
    ({"balance_gains": (2.0, 0.0)}, r"problem.balance_gains\[0\]"),
    ({"balance_gains": (0.0, float("nan"))}, r"problem.balance_gains\[1\]"),
    ({"control_period_s": 0.0}, "problem.control_period_s"),
])
def test_bad_settings_are_one_line(cfg, match):
    with pytest.raises(InputError, match=match):
        KickConfig(**cfg).validate()


def test_a_period_off_the_physics_step_is_refused():
    with pytest.raises(InputError, match="problem.control_period_s: 0.01 s is not a whole"):
        KickProblem(KickConfig(balance_gains=(0.05, 0.0), control_period_s=0.01))
    KickProblem(KickConfig(control_period_s=0.01))  # the open-loop kick does not read it


def test_feedback_needs_a_control_period(scene):
    p, worlds, ctrl, s0 = scene
    with pytest.raises(InputError, match="feedback runs on the CPU"):
        simulate_worlds(worlds, s0, ctrl, 1, feedback=lambda r, t, s: 0, control_steps=0)
