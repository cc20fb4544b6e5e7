"""The closed loop on MuJoCo Warp (sim/warp_closed_loop.py) against the CPU closed loop, on
Warp's CPU device (the same code runs on a CUDA GPU; benchmarks/bench_gpu.py measures it).

Tolerances (float32 against float64; measured on 8 drawn NAO worlds with pushes up to 6 N s
under a random linear policy: joint angles and torso pose <= 3.2e-6 and velocities <= 2.3e-4
over 1 s, the same falls at the same physics step): positions within 1e-4 and velocities
within 1e-2 over the first 0.3 s; over 1 s the same robots fall, within 2 physics steps.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("mujoco_warp")

from evomotion.core.policies import make_policy  # noqa: E402
from evomotion.errors import InputError  # noqa: E402
from evomotion.sim.closed_loop import ClosedLoopSimulator  # noqa: E402
from evomotion.sim.observations import (  # noqa: E402
    CHANNELS,
    ObservationBuilder,
    ObservationSpec,
)
from evomotion.sim.robots import load_robot  # noqa: E402
from evomotion.sim.warp_closed_loop import WarpClosedLoopSimulator  # noqa: E402
from evomotion.sim.warp_policy import PopulationPolicy, on_device  # noqa: E402
from evomotion.sim.worlds import Perturbation, draw_worlds, make_world  # noqa: E402

SPEC = ObservationSpec(("joint_pos", "joint_vel", "gravity", "gyro", "foot_contact", "phase"),
                       phase_period_s=0.5)
K = 5  # 20 ms control period on the NAO's 4 ms steps
POS_TOL, VEL_TOL = 1e-4, 1e-2


@pytest.fixture(scope="module")
def robot():
    return load_robot("nao")


@pytest.fixture(scope="module")
def sim(robot):
    return WarpClosedLoopSimulator(robot, SPEC, K, device="cpu")


def zero(rows, obs):
    return np.zeros((rows.size, 10))


def linear(sim, robot, n, seed, kind="linear", **opts):
    nominal = robot.pose[sim.columns]
    spec = make_policy(kind, sim.observation_size, sim.action_size, scale=0.3,
                       low=sim.lower - nominal, high=sim.upper - nominal, clip_obs=5.0, **opts)
    rng = np.random.default_rng(seed)
    o = sim.observation_size
    return PopulationPolicy(spec, 0.02 * rng.standard_normal((n, spec.n_params)),
                            0.01 * rng.standard_normal((n, o)), 1.0 + rng.random((n, o)))


@pytest.fixture(scope="module")
def episodes(robot, sim):
    """8 drawn worlds, pushes up to 6 N s, 1 s under a linear policy: (warp, cpu, worlds)."""
    rng = np.random.default_rng(0)
    worlds = draw_worlds(robot.model, Perturbation(push_ns=(0.0, 6.0), push_at=(0.1, 0.5)), 8,
                         rng, 1.0)
    policy = linear(sim, robot, 8, 1)
    warp = sim.run(policy, worlds, 250, record_states=True, record_targets=True)
    with ClosedLoopSimulator(robot, SPEC, K) as cpu_sim:
        cpu = cpu_sim.run(policy, worlds, 250, record_states=True, record_targets=True)
    return warp, cpu, worlds, policy


def test_first_0_3_s_agree_with_the_cpu_closed_loop(robot, episodes):
    warp, cpu, _, _ = episodes
    assert warp.policy_on == "device" and warp.device == "cpu"
    nq, early = robot.model.nq, 16  # control steps: 0.32 s
    pos = np.abs(warp.states[:, :early, 1:1 + nq] - cpu.states[:, :early, 1:1 + nq]).max()
    vel = np.abs(warp.states[:, :early, 1 + nq:] - cpu.states[:, :early, 1 + nq:]).max()
    assert pos < POS_TOL and vel < VEL_TOL, (pos, vel)
    np.testing.assert_allclose(warp.targets[:, :early], cpu.targets[:, :early], atol=1e-3)
    np.testing.assert_allclose(warp.obs_sum / warp.obs_count[:, None],
                               cpu.obs_sum / cpu.obs_count[:, None], atol=1e-2)
    assert np.abs(warp.targets[:, :early] - robot.pose[robot.columns]).max() > 1e-3  # acted


def test_one_second_gives_the_same_falls(episodes):
    warp, cpu, _, _ = episodes
    assert warp.fell.any() and not warp.fell.all()  # the test can tell
    np.testing.assert_array_equal(warp.fell, cpu.fell)
    assert np.abs(warp.fall_step - cpu.fall_step).max() <= 2
    np.testing.assert_array_equal(warp.steps, np.minimum(K * (warp.fall_step // K + 1), 250))
    assert warp.torso.shape == cpu.torso.shape and warp.states.shape == cpu.states.shape


def test_host_policy_equals_the_device_policy_within_float32(sim, episodes):
    warp, _, worlds, policy = episodes
    calls = []

    def host(rows, obs):
        calls.append(rows.copy())
        assert not rows.flags.writeable and obs.dtype == np.float64
        return policy(rows, obs)

    res = sim.run(host, worlds[:4], 100, record_states=True)
    assert res.policy_on == "host" and len(calls) == 20
    assert all(c.size <= 4 for c in calls)
    assert np.abs(res.states[:, :16, 1:30] - warp.states[:4, :16, 1:30]).max() < POS_TOL


def test_mlp_runs_on_the_device_and_matches_the_cpu(robot, sim):
    policy = linear(sim, robot, 2, 4, kind="mlp", hidden=(8,))
    assert on_device(policy)
    warp = sim.run(policy, 2, 40, record_targets=True)
    with ClosedLoopSimulator(robot, SPEC, K) as cpu_sim:
        cpu = cpu_sim.run(policy, 2, 40, record_targets=True)
    assert warp.policy_on == "device"
    np.testing.assert_allclose(warp.targets, cpu.targets, atol=1e-4)


def test_other_policies_run_on_the_host(robot, sim):
    names = list(sim.observe.names)
    spec = make_policy("structured", sim.observation_size, sim.action_size, harmonics=1,
                       phase_columns=(names.index("phase:sin"), names.index("phase:cos")))
    policy = PopulationPolicy(spec, np.zeros((2, spec.n_params)), 0.0, 1.0)
    assert not on_device(policy)
    res = sim.run(policy, 2, 10)
    assert res.policy_on == "host" and (res.steps == 10).all()


def test_a_trajectory_does_not_depend_on_its_batch(robot, sim, episodes):
    """Alone, among others, packed into a smaller batch after others fell: bit for bit."""
    warp, _, worlds, policy = episodes
    rows = [1, 7, 3]  # two fall, 7 stands: the batch of 4 packs to 1
    sub = PopulationPolicy(policy.spec, policy.params[rows], policy.mean[rows],
                           policy.std[rows])
    three = sim.run(sub, [worlds[i] for i in rows], 250, record_states=True)
    alone = sim.run(PopulationPolicy(policy.spec, policy.params[7:8], policy.mean[7:8],
                                     policy.std[7:8]), [worlds[7]], 250, record_states=True)
    np.testing.assert_array_equal(three.states[1], warp.states[7])
    np.testing.assert_array_equal(alone.states[0], warp.states[7])
    np.testing.assert_array_equal(three.obs_sum[1], warp.obs_sum[7])


def test_early_stop_drops_fallen_worlds(robot, sim):
    """World 1 falls first and leaves the batch of 4; when 2 and 3 have fallen too, world 0
    is packed into a batch of 1."""
    worlds = [make_world(robot.model)] + [
        make_world(robot.model, push_ns=(0.0, 30.0, 0.0), push_time_s=t)
        for t in (0.02, 0.3, 0.4)]
    calls = []

    def policy(rows, obs):
        calls.append(rows.copy())
        return np.zeros((rows.size, 10))

    before = sim.steps_simulated
    res = sim.run(policy, worlds, 200, record_states=True)
    assert res.fell.tolist() == [False, True, True, True]
    fall = int(res.fall_step[1])
    gone = fall // K + 1
    assert 5 < fall < res.fall_step[2] and res.steps[1] == K * gone
    assert res.obs_count[1] == gone and res.obs_count[0] == 40
    assert all(1 in c for c in calls[:gone]) and all(1 not in c for c in calls[gone:])
    assert [c.size for c in calls][-1] == 1 and len(calls) == 40
    assert sim.steps_simulated - before < 4 * 200  # packed into a batch of 1
    np.testing.assert_array_equal(res.torso[1, gone:], np.broadcast_to(res.torso[1, gone],
                                                                       res.torso[1, gone:].shape))
    with ClosedLoopSimulator(robot, SPEC, K) as cpu_sim:
        cpu = cpu_sim.run(zero, worlds, 200)
    np.testing.assert_array_equal(res.fall_step, cpu.fall_step)


def test_latency_and_pushes_act_as_on_the_cpu(robot, sim):
    worlds = [make_world(robot.model, latency_steps=7),
              make_world(robot.model, latency_steps=2, push_ns=(0.0, 2.0, 0.0),
                         push_time_s=0.1),
              make_world(robot.model, push_ns=(0.0, -2.0, 0.0), push_time_s=0.05)]
    count = [0]

    def step(rows, obs):  # the first driven joint +0.3 rad from control step 2
        out = np.zeros((rows.size, 10))
        out[:, 0] = 0.3 if count[0] >= 2 else 0.0
        count[0] += 1
        return out

    res = sim.run(step, worlds, 75, record_states=True)
    count[0] = 0
    with ClosedLoopSimulator(robot, SPEC, K) as cpu_sim:
        cpu = cpu_sim.run(step, worlds, 75, record_states=True)
    still = sim.run(zero, worlds, 75, record_states=True).states
    assert np.abs(res.states[..., 1:30] - cpu.states[..., 1:30]).max() < POS_TOL
    # world 0: the new target acts from physics step 2 * K + 7 = 17 (in control step 3)
    np.testing.assert_array_equal(res.states[0, :4], still[0, :4])
    assert not np.array_equal(res.states[0, 4], still[0, 4])
    vy = res.torso[..., 8]  # after the pushes (steps 25 and 12): +-2 N s / 5.3 kg
    assert vy[1, 6] > 0.2 and vy[2, 3] < -0.2 and np.abs(vy[1, :5]).max() < 0.05


def test_buffers_grow_without_calling_the_policy_twice(robot):
    small = WarpClosedLoopSimulator(robot, SPEC, K, device="cpu", nconmax=1, njmax=4)
    calls = []

    def policy(rows, obs):
        calls.append(rows.size)
        return np.zeros((rows.size, 10))

    res = small.run(policy, 2, 20, record_states=True)
    assert small.regrown >= 1 and len(calls) == 4
    ref = WarpClosedLoopSimulator(robot, SPEC, K, device="cpu").run(zero, 2, 20,
                                                                     record_states=True)
    np.testing.assert_array_equal(res.states, ref.states)


def test_bad_settings_are_one_line_errors(robot, sim, episodes):
    _, _, worlds, policy = episodes
    with pytest.raises(InputError, match="control_steps"):
        WarpClosedLoopSimulator(robot, SPEC, 0, device="cpu")
    with pytest.raises(InputError, match="problem.warp_device"):
        WarpClosedLoopSimulator(robot, SPEC, K, device="tpu:3")
    with pytest.raises(InputError, match="8 parameter rows for 2"):
        sim.run(policy, 2, 10)
    small = make_policy("linear", 3, sim.action_size)
    with pytest.raises(InputError, match="maps 3 observations"):
        sim.run(PopulationPolicy(small, np.zeros((2, small.n_params)), 0.0, 1.0), 2, 10)
    with pytest.raises(ValueError, match="policy returned shape"):
        sim.run(lambda rows, obs: np.zeros((rows.size, 3)), 2, 10)
    with pytest.raises(InputError, match="world 1"):
        sim.run(zero, [make_world(robot.model), make_world(load_robot("op3").model)], 10)
    with pytest.raises(InputError, match="initial_state"):
        sim.run(zero, 2, 10, initial_state=np.zeros(5))


@settings(max_examples=15, deadline=None)
@given(st.permutations(sorted(CHANNELS)), st.integers(1, len(CHANNELS)), st.integers(0, 99))
def test_device_observations_equal_the_host_builder(robot, channels, size, seed):
    """Every channel, in any order, on random states: the observe kernel against numpy."""
    import warp as wp

    from evomotion.sim import warp_closed_loop_kernels as kern
    from evomotion.sim.warp_batch import column_table

    spec = ObservationSpec(tuple(channels[:size]), phase_period_s=0.7, command_size=2)
    build = ObservationBuilder(spec, robot)
    m, rng, n = robot.model, np.random.default_rng(seed), 5
    states = np.tile(robot.state0, (n, 1))
    states[:, 0] = rng.uniform(0, 3, n)
    q = rng.standard_normal((n, 4))
    states[:, 4:8] = q / np.linalg.norm(q, axis=1, keepdims=True)
    states[:, 1 + m.nq:] = rng.standard_normal((n, m.nv))
    states[:, 8:1 + m.nq] += 0.1 * rng.standard_normal((n, m.nq - 7))
    sensors = rng.uniform(-1, 1, (n, m.nsensordata))
    commands = rng.standard_normal((n, 2))
    want = build(states, sensors, commands)
    kind, index = column_table(build, robot)
    f32 = np.float32
    arr = [wp.array(a.astype(f32), dtype=float, device="cpu") for a in
           (states[:, 1:1 + m.nq], states[:, 1 + m.nq:], states[:, 0], sensors, commands)]
    out = wp.zeros((n, build.size), dtype=float, device="cpu")
    wp.launch(kern.observe, dim=(n, build.size), device="cpu",
              inputs=[*arr, wp.array(kind, dtype=int, device="cpu"),
                      wp.array(index, dtype=int, device="cpu"), int(m.jnt_qposadr[0]),
                      int(m.jnt_dofadr[0]), 2 * np.pi / 0.7], outputs=[out])
    np.testing.assert_allclose(out.numpy(), want, atol=2e-5, rtol=1e-5)
