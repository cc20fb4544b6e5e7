"""Closed-loop population rollouts (sim/closed_loop.py) against the open-loop paths."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.errors import InputError
from evomotion.sim.closed_loop import ClosedLoopSimulator, total_moments
from evomotion.sim.closed_loop_parts import TargetFifo
from evomotion.sim.observations import ObservationSpec
from evomotion.sim.robots import load_robot
from evomotion.sim.rollout import BatchSimulator, fall_step, torso_track
from evomotion.sim.worlds import Perturbation, draw_worlds, make_world, simulate_worlds

SPEC = ObservationSpec(("joint_pos", "joint_vel", "gravity", "gyro", "foot_contact", "phase"),
                       phase_period_s=0.5)


@pytest.fixture(scope="module")
def robot():
    return load_robot("nao")


def zero(rows, obs):
    return np.zeros((rows.size, 10))


def never(states):
    return np.zeros(states.shape[0], dtype=bool)


def open_loop_segments(robot, ctrl, k, nthread=1):
    """The open-loop path of sim/rollout.py stepped in k-step segments: states[n, T, ns]."""
    with BatchSimulator(robot.model, nthread) as sim:
        return sim.run_until(robot.state0, ctrl, never, k)[0]


def test_zero_policy_equals_the_open_loop_holding_the_pose(robot):
    n, nstep, k = 3, 60, 4
    with ClosedLoopSimulator(robot, SPEC, k, nthread=2) as sim:
        res = sim.run(zero, n, nstep, record_states=True)
    ctrl = np.broadcast_to(robot.pose, (n, nstep, robot.model.nu))
    ol = open_loop_segments(robot, ctrl, k)
    np.testing.assert_array_equal(res.states[:, 1:], ol[:, k - 1::k])  # exactly
    np.testing.assert_array_equal(res.states[:, 0], np.broadcast_to(robot.state0, (n, ol.shape[2])))
    with BatchSimulator(robot.model, 1) as one_call:  # no warm start reset between calls
        whole = one_call.run(robot.state0, ctrl)
    np.testing.assert_allclose(res.states[:, 1:], whole[:, k - 1::k], atol=1e-6)
    np.testing.assert_array_equal(res.torso[..., :7], res.states[..., 1:8])
    assert not res.fell.any() and (res.fall_step == nstep).all() and (res.steps == nstep).all()


def test_policy_called_once_per_control_step_with_running_rows(robot):
    calls = []

    def policy(rows, obs):
        calls.append((rows, obs.copy()))
        return np.zeros((rows.size, 10))

    n, nstep, k = 4, 23, 5  # the last control period is 3 steps long
    with ClosedLoopSimulator(robot, SPEC, k) as sim:
        res = sim.run(policy, n, nstep)
    assert len(calls) == 5 and res.torso.shape == (n, 6, 13)
    for rows, obs in calls:
        np.testing.assert_array_equal(rows, np.arange(n))
        assert not rows.flags.writeable
        assert obs.shape == (n, sim.observation_size)
    last = calls[-1][1]  # standing: both soles on the floor, upright, clock at 20 ms steps
    np.testing.assert_array_equal(last[:, sim.observe.slices["foot_contact"]], 1.0)
    np.testing.assert_allclose(last[:, sim.observe.slices["gravity"]], [[0, 0, -1]] * n,
                               atol=0.05)
    phase = 2 * np.pi * 4 * k * robot.model.opt.timestep / 0.5
    np.testing.assert_allclose(last[:, sim.observe.slices["phase"]],
                               [[np.sin(phase), np.cos(phase)]] * n, atol=1e-9)
    assert (res.steps == nstep).all() and (res.obs_count == 5).all()


def test_a_fallen_individual_leaves_the_batch(robot):
    worlds = [make_world(robot.model), make_world(robot.model, push_ns=(0.0, 30.0, 0.0),
                                                  push_time_s=0.02), make_world(robot.model)]
    calls = []

    def policy(rows, obs):
        calls.append(rows.copy())
        return np.zeros((rows.size, 10))

    nstep, k = 200, 5
    with ClosedLoopSimulator(robot, SPEC, k) as sim:
        res = sim.run(policy, worlds, nstep, record_states=True)
    assert res.fell.tolist() == [False, True, False]
    fall = int(res.fall_step[1])
    assert 5 < fall < nstep and res.steps[1] == k * (fall // k + 1)
    assert res.steps[0] == res.steps[2] == nstep
    ol = simulate_worlds(worlds, robot.state0, np.broadcast_to(robot.pose, (nstep, 22)),
                         stopped=never, segment_steps=k, nthread=1)
    np.testing.assert_array_equal(
        res.fall_step, fall_step(torso_track(ol), robot.fall_height_m, robot.fall_tilt_rad))
    dt = robot.model.opt.timestep
    np.testing.assert_allclose(res.fall_time_s, [nstep * dt, (fall + 1) * dt, nstep * dt])
    gone = fall // k + 1  # control steps taken by the fallen one
    assert all(1 in c for c in calls[:gone]) and all(1 not in c for c in calls[gone:])
    assert len(calls) == nstep // k and res.obs_count[1] == gone
    np.testing.assert_array_equal(res.torso[1, gone:], np.broadcast_to(res.torso[1, gone],
                                                                       res.torso[1, gone:].shape))


def _step_policy(change_at):
    """A policy that moves the first driven joint by +0.3 rad from control step change_at."""
    count = [0]

    def policy(rows, obs):
        out = np.zeros((rows.size, 10))
        out[:, 0] = 0.3 if count[0] >= change_at else 0.0
        count[0] += 1
        return out
    return policy


@pytest.mark.parametrize("latency", [3, 7])
def test_latency_delays_the_targets_by_its_physics_steps(robot, latency):
    n, nstep, k, change = 2, 40, 5, 2
    worlds = [make_world(robot.model), make_world(robot.model, latency_steps=latency)]
    with ClosedLoopSimulator(robot, SPEC, k) as sim:
        res = sim.run(_step_policy(change), worlds, nstep, record_states=True)
    ctrl = np.broadcast_to(robot.pose, (n, nstep, robot.model.nu)).copy()
    col = robot.columns[0]
    ctrl[:, change * k:, col] = np.clip(robot.pose[col] + 0.3, robot.lower[0], robot.upper[0])
    ctrl[1] = np.concatenate([np.broadcast_to(robot.pose, (latency, robot.model.nu)),
                              ctrl[1, :nstep - latency]])
    ol = open_loop_segments(robot, ctrl, k)
    np.testing.assert_array_equal(res.states[:, 1:], ol[:, k - 1::k])
    with ClosedLoopSimulator(robot, SPEC, k) as sim:
        still = sim.run(zero, worlds, nstep, record_states=True).states
    # states[:, c] follow c * k physics steps: the new target acts from step change * k + d
    for i, d in enumerate((0, latency)):
        arrive = (change * k + d) // k
        np.testing.assert_array_equal(res.states[i, :arrive + 1], still[i, :arrive + 1])
        assert not np.array_equal(res.states[i, arrive + 1], still[i, arrive + 1])


def test_pushes_and_latency_equal_the_open_loop_worlds(robot):
    worlds = [make_world(robot.model, latency_steps=2, push_ns=(0.0, 2.0, 0.0),
                         push_time_s=0.1),
              make_world(robot.model, friction_scale=0.8, mass_scale=1.05,
                         push_ns=(0.0, -2.0, 0.0), push_time_s=0.05),
              make_world(robot.model)]
    nstep, k = 75, 3
    with ClosedLoopSimulator(robot, SPEC, k, nthread=2) as sim:
        res = sim.run(zero, worlds, nstep, record_states=True)
    ol = simulate_worlds(worlds, robot.state0, np.broadcast_to(robot.pose, (nstep, 22)),
                         nthread=1, stopped=never, segment_steps=k)
    np.testing.assert_array_equal(res.states[:, 1:], ol[:, k - 1::k])
    vy = res.torso[..., 8]  # the torso's world velocity along y, just after the pushes:
    assert vy[0, 9] > 0.2 and vy[1, 5] < -0.2  # steps 25 and 12 (+-2 N s / 5.3 kg = 0.38 m/s)
    assert np.abs(vy[2]).max() < 0.05 and np.abs(vy[0, :8]).max() < 0.05


def test_push_over_several_steps_gives_the_same_impulse(robot):
    w = [make_world(robot.model, push_ns=(0.0, 2.5, 0.0), push_time_s=0.04)]
    out = {}
    for steps in (1, 5):
        with ClosedLoopSimulator(robot, SPEC, 5, push_steps=steps) as sim:
            out[steps] = sim.run(zero, w, 25).torso[0, -1]
    mass = robot.model.body_mass.sum()
    assert out[1][8] == pytest.approx(out[5][8], abs=0.05)
    assert 0.5 * 2.5 / mass < out[5][8] < 1.5 * 2.5 / mass


def test_runs_are_bit_identical_twice_and_for_any_thread_count(robot):
    worlds = [make_world(robot.model, latency_steps=i % 3, push_ns=(0.0, 1.0 - i, 0.0),
                         push_time_s=0.03 * i) for i in range(4)]
    gain = 0.05 * np.random.default_rng(3).standard_normal((4, 10, 32))
    commands = np.array([[0.5, -0.2], [0.1, 0.0], [0.0, 0.3], [-0.4, 0.2]])

    def policy(rows, obs):
        return np.einsum("nao,no->na", gain[rows], obs)

    spec = ObservationSpec(SPEC.channels + ("command",), phase_period_s=0.5, command_size=2)
    results = []
    for nthread in (1, 2, 2):
        with ClosedLoopSimulator(robot, spec, 3, nthread=nthread) as sim:
            results.append(sim.run(policy, worlds, 45, commands=commands,
                                   record_states=True, record_targets=True))
    for other in results[1:]:
        for name in ("torso", "fell", "fall_step", "steps", "obs_count", "obs_sum",
                     "obs_sumsq", "states", "targets"):
            np.testing.assert_array_equal(getattr(results[0], name), getattr(other, name))


def test_moments_match_numpy_over_the_observations(robot):
    seen = []

    def policy(rows, obs):
        seen.append((rows.copy(), obs.copy()))
        return 0.05 * np.tanh(obs[:, :10])

    worlds = [make_world(robot.model), make_world(robot.model, push_ns=(0.0, 25.0, 0.0),
                                                  push_time_s=0.0)]
    with ClosedLoopSimulator(robot, SPEC, 4) as sim:
        res = sim.run(policy, worlds, 120)
    assert res.fell.tolist() == [False, True]
    for i in range(2):
        obs = np.array([o[list(r).index(i)] for r, o in seen if i in r])
        assert res.obs_count[i] == len(obs)
        np.testing.assert_allclose(res.obs_sum[i] / len(obs), obs.mean(axis=0), rtol=1e-12,
                                   atol=1e-12)
        var = res.obs_sumsq[i] / len(obs) - (res.obs_sum[i] / len(obs)) ** 2
        np.testing.assert_allclose(var, obs.var(axis=0), rtol=1e-9, atol=1e-12)
    count, total, totalsq = total_moments(res)
    allobs = np.concatenate([o for _, o in seen])
    assert count == len(allobs)
    np.testing.assert_allclose(total, allobs.sum(axis=0), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(totalsq, (allobs ** 2).sum(axis=0), rtol=1e-12, atol=1e-12)


def test_actions_are_offsets_clipped_to_the_joint_ranges(robot):
    def wild(rows, obs):
        out = np.full((rows.size, 10), 10.0)
        out[:, 1] = -10.0
        out[:, 2] = np.nan
        return out

    with ClosedLoopSimulator(robot, SPEC, 5) as sim:
        res = sim.run(wild, 2, 10, record_targets=True)
    t = res.targets[0, 0]
    assert t[0] == robot.upper[0] and t[1] == robot.lower[1]
    assert t[2] == robot.pose[robot.columns[2]]


def test_bad_inputs_are_refused(robot):
    with pytest.raises(InputError):
        ClosedLoopSimulator(robot, SPEC, 0)
    with pytest.raises(InputError):
        ObservationSpec(("joint_pos", "nose")).validate()
    with ClosedLoopSimulator(robot, SPEC, 5) as sim:
        with pytest.raises(ValueError, match="policy returned shape"):
            sim.run(lambda rows, obs: np.zeros((rows.size, 3)), 2, 10)
        with pytest.raises(InputError):
            sim.run(zero, 0, 10)


@pytest.mark.parametrize("kw", [{"initial_state": np.zeros(5)},
                                {"initial_state": np.full((3, 58), np.nan)},
                                {"commands": np.zeros((4, 3))}])
def test_bad_run_arguments_are_one_line_errors(robot, kw):
    spec = ObservationSpec(("gyro", "command"), command_size=2)
    with ClosedLoopSimulator(robot, spec, 5) as sim, pytest.raises(InputError,
                                                                   match="closed loop"):
        sim.run(zero, 3, 10, **{"commands": np.zeros(2)} | kw)


def test_drawn_worlds_equal_the_open_loop_worlds(robot):
    nstep, k = 50, 5
    worlds = draw_worlds(robot.model, Perturbation(push_at=(0.1, 0.5)), 3,
                         np.random.default_rng(11), nstep * robot.model.opt.timestep)
    with ClosedLoopSimulator(robot, SPEC, k, nthread=2) as sim:
        res = sim.run(zero, worlds, nstep, record_states=True)
    ol = simulate_worlds(worlds, robot.state0, np.broadcast_to(robot.pose, (nstep, 22)),
                         nthread=2, stopped=never, segment_steps=k)
    np.testing.assert_array_equal(res.states[:, 1:], ol[:, k - 1::k])


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 6), st.lists(st.integers(0, 13), min_size=1, max_size=4),
       st.integers(1, 30))
def test_target_fifo_is_a_delay_line(k, latency, nstep):
    n, nu = len(latency), 2
    targets = np.random.default_rng(k).random((n, -(-nstep // k), nu))
    fifo = TargetFifo(n, np.array([-1.0, -2.0]), np.array(latency), k)
    rows = np.arange(n)
    got = []
    for c in range(targets.shape[1]):
        fifo.push(rows, c, targets[:, c])
        got.append(fifo.controls(rows, c * k, min(k, nstep - c * k)))
    got = np.concatenate(got, axis=1)
    for i, d in enumerate(latency):
        for t in range(nstep):
            want = targets[i, (t - d) // k] if t >= d else [-1.0, -2.0]
            np.testing.assert_array_equal(got[i, t], want)


def test_worlds_of_another_robot_are_refused(robot):
    other = make_world(load_robot("op3").model)
    with ClosedLoopSimulator(robot, SPEC, 5) as sim, pytest.raises(InputError, match="world 1"):
        sim.run(zero, [make_world(robot.model), other], 10)


def test_a_command_schedule_feeds_each_control_step_its_command(robot):
    """commands[n, C, m]: control step c observes commands[:, c]; a held [n, m] command is the
    same as that schedule repeated."""
    spec = ObservationSpec(("gyro", "command"), command_size=2)
    n, k, nstep = 2, 3, 12
    C = nstep // k
    sched = np.arange(n * C * 2, dtype=float).reshape(n, C, 2)
    seen = []

    def policy(rows, obs):
        seen.append(obs[:, -2:].copy())
        return np.zeros((rows.size, 10))

    with ClosedLoopSimulator(robot, spec, k) as sim:
        sim.run(policy, n, nstep, commands=sched)
        np.testing.assert_array_equal(np.stack(seen, axis=1), sched)
        seen.clear()
        sim.run(policy, n, nstep, commands=sched[:, 0])
        np.testing.assert_array_equal(np.stack(seen, axis=1),
                                      np.repeat(sched[:, :1], C, axis=1))
        with pytest.raises(InputError, match="command schedule"):
            sim.run(policy, n, nstep, commands=sched[:, :-1])


def test_a_follower_actuator_copies_its_leader(robot):
    """followers=[(f, l)]: actuator f gets actuator l's target (the NAO's hip yaw-pitch is one
    motor); the targets the servos receive equal an open-loop run with that copy made."""
    from evomotion.sim.robots import nao

    col = {j: i for i, j in enumerate(nao.JOINTS)}
    lead, follow = col["LHipYawPitch"], col["RHipYawPitch"]
    cols = [*robot.columns, lead]
    n, k, nstep = 2, 4, 40

    def policy(rows, obs):
        a = np.zeros((rows.size, len(cols)))
        a[:, -1] = -0.3
        return a

    with ClosedLoopSimulator(robot, SPEC, k, columns=cols,
                             followers=[(follow, lead)]) as sim:
        res = sim.run(policy, n, nstep, record_states=True)
    ctrl = np.broadcast_to(robot.pose, (n, nstep, robot.model.nu)).copy()
    ctrl[..., lead] = ctrl[..., follow] = robot.pose[lead] - 0.3
    states = open_loop_segments(robot, ctrl, k)
    np.testing.assert_array_equal(res.states[:, -1], states[:, -1])
    with pytest.raises(InputError, match="followers"):
        ClosedLoopSimulator(robot, SPEC, k, columns=cols, followers=[(lead, follow)])
