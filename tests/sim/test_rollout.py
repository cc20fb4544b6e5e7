import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.sim.robots import nao
from evomotion.sim.rollout import (
    BatchSimulator,
    TorsoTrack,
    fall_step,
    interpolate_controls,
    torso_track,
)


@settings(max_examples=30, deadline=None)
@given(st.integers(2, 8), st.integers(0, 10_000))
def test_interpolate_controls_hits_keys_and_is_linear(nkeys, seed):
    rng = np.random.default_rng(seed)
    dt = 0.004
    times = np.arange(nkeys) * 0.04
    values = rng.normal(size=(3, nkeys, 2))
    nstep = int(round(times[-1] / dt)) + 5
    ctrl = interpolate_controls(times, values, dt, nstep)
    t = dt * np.arange(nstep)
    for k in range(1, nkeys):
        i = int(round(times[k] / dt))
        np.testing.assert_allclose(ctrl[:, i], values[:, k], atol=1e-9)
    expected = np.stack([[np.interp(t, times, values[b, :, j]) for j in range(2)]
                         for b in range(3)]).transpose(0, 2, 1)
    np.testing.assert_allclose(ctrl, expected, atol=1e-12)


def test_fall_step_first_fallen_step():
    z = np.full((2, 10), 0.3)
    up = np.ones((2, 10))
    z[0, 6:] = 0.1
    up[1, 3] = 0.5
    track = TorsoTrack(np.stack([np.zeros_like(z), np.zeros_like(z), z], -1), up, np.zeros_like(z))
    assert fall_step(track, 0.2, np.pi / 4).tolist() == [6, 3]
    up[1, 3] = 0.9
    assert fall_step(track, 0.2, np.pi / 4).tolist() == [6, 10]


def test_threads_give_identical_states():
    model = nao.load_model()
    rng = np.random.default_rng(0)
    ctrl = nao.pose_vector() + rng.normal(0, 0.05, size=(4, 100, model.nu))
    s0 = nao.initial_state(model)
    with BatchSimulator(model, 1) as one, BatchSimulator(model, 2) as two:
        a, b = one.run(s0, ctrl), two.run(s0, ctrl)
    np.testing.assert_array_equal(a, b)
    track = torso_track(a)
    assert track.xyz.shape == (4, 100, 3)


def test_run_until_stops_fallen_trajectories():
    model = nao.load_model()
    s0 = nao.initial_state(model)
    ctrl = np.tile(nao.pose_vector(), (3, 60, 1))
    calls = []

    def stopped(seg):
        calls.append(seg.shape[0])
        return np.array([True, False, False])[: seg.shape[0]] if len(calls) == 1 else \
            np.zeros(seg.shape[0], bool)

    with BatchSimulator(model, 1) as sim:
        states, sensors = sim.run_until(s0, ctrl, stopped, segment_steps=20)
        assert sim.steps_simulated == 3 * 20 + 2 * 40
    assert calls == [3, 2, 2]
    np.testing.assert_array_equal(states[0, 20:], np.broadcast_to(states[0, 19], (40, 58)))
    assert sensors.shape == (3, 60, 6)
    assert not np.array_equal(states[1, 20:30], np.broadcast_to(states[1, 19], (10, 58)))
