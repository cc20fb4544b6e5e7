"""The capture step (capture_step.py): leg odometry reads the torso's velocity (the hip
yaw-pitch's rate counted while turning), the swing foot lands at the clipped capture-point
offset, the sway is learnt only from calm steps, gain 0 changes nothing, other robots are
refused, a run exports it and the policy player runs it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.sim.closed_loop import ClosedLoopSimulator
from evomotion.sim.observations import ObservationSpec
from evomotion.studies.humanoid_omniwalk.capture_step import (
    DEADBAND_MPS,
    REACH_X_M,
    CaptureStep,
)
from evomotion.studies.humanoid_omniwalk.controller import CHANNELS
from evomotion.studies.humanoid_omniwalk.problem import OmniWalkConfig, OmniWalkProblem
from evomotion.studies.policy_search import policy_rows


@pytest.fixture(scope="module")
def problem():
    return OmniWalkProblem(OmniWalkConfig(duration_s=3.0, threads=1, capture_gain=1.0))


def _reading(ctl) -> tuple[ClosedLoopSimulator, list[str], list[int]]:
    """The controller's simulator with the torso's true velocity appended, its observation
    names and the true velocity's x, y columns."""
    spec = ObservationSpec((*CHANNELS, "torso_velocity"), phase_period_s=ctl.gait.period_s,
                           command_size=3)
    sim = ctl.simulator(spec, 1)
    names = list(sim.observe.names)
    return sim, names, [names.index(f"torso_velocity:{a}") for a in "xy"]


def test_leg_odometry_reads_the_torsos_velocity(problem):
    """The fitted engine walking forward at 0.3 m/s, then sideways at 0.15, nominal world:
    after the first cycle, eq. (1)'s mean velocity within 2 cm/s of the true one and each
    axis correlated above 0.85 with it, control step by control step (measured 0.92-0.95;
    this engine sways 0.33 m/s sideways and its mean |error| is 2.5-6 cm/s)."""
    ctl = problem.ctl
    sim, names, true_cols = _reading(ctl)
    x, od = ctl.initial_params(), problem.obs_dim
    seen = []
    for command in ((0.3, 0.0, 0.0), (0.0, 0.15, 0.0)):
        layer = CaptureStep(ctl, names, 1, 0.0)

        def policy(rows, obs, layer=layer):
            act = problem.policy.act(x[None], obs[:, :od], np.zeros((1, od)), np.ones((1, od)))
            est = layer.velocity_of(rows, obs, layer.phase(obs))
            seen.append((est[0], obs[0, true_cols]))
            return layer(rows, obs, act)

        res = sim.run(policy, 1, int(2.0 / problem.dt), commands=np.array([command]),
                      initial_state=ctl.state0)
        assert not res.fell[0]
    sim.close()
    half = len(seen) // 2
    for part in (seen[ctl.window:half], seen[half + ctl.window:]):
        est, true = (np.array(a) for a in zip(*part, strict=True))
        np.testing.assert_allclose(est.mean(axis=0), true.mean(axis=0), atol=0.02)
        for axis in range(2):
            assert np.corrcoef(est[:, axis], true[:, axis])[0, 1] > 0.85


def test_gain_zero_returns_the_action_unchanged(problem):
    ctl = problem.ctl
    names = list(ctl.sim.observe.names)
    rng = np.random.default_rng(0)
    obs = rng.normal(size=(5, len(names)))
    act = rng.normal(size=(5, ctl.columns.size))
    layer = CaptureStep(ctl, names, 5, 0.0)
    assert np.array_equal(layer(np.arange(5), obs, act), act)


def test_the_swing_foot_lands_at_the_clipped_capture_point(problem):
    """A constant velocity offset (an oracle column, a fixed sway of 0): over one cycle each
    foot ends its swing at ``gain Δv / ω₀`` (``|Δv|`` less the dead band; x clipped to
    REACH_X_M, y outward only) and keeps it while it stands."""
    ctl = problem.ctl
    names = [*ctl.sim.observe.names, "torso_velocity:x", "torso_velocity:y"]
    vcols = [len(names) - 2, len(names) - 1]
    omega = math.sqrt(9.81 / ctl.com_height_m)
    dv = np.array([[0.3, 0.0], [2.0, 0.3]])  # 0.3 m/s forward; far beyond reach, to the left
    layer = CaptureStep(ctl, names, 2, 1.0, velocity=vcols, sway=np.zeros((ctl.window, 2)))
    obs = np.zeros((2, len(names)))
    obs[:, vcols] = dv
    action = np.zeros((2, ctl.columns.size))
    outs, offsets, phases = [], [], []
    for c in range(2 * ctl.window):
        phase = c * ctl.control_dt / ctl.gait.period_s
        obs[:, names.index("phase:sin")] = math.sin(2 * math.pi * phase)
        obs[:, names.index("phase:cos")] = math.cos(2 * math.pi * phase)
        outs.append(layer(np.arange(2), obs, action))
        offsets.append(layer.offset.copy())
        phases.append(phase % 1.0)
    off, ph = np.array(offsets), np.array(phases)  # [T, 2 worlds, 2 feet, 2]
    w = ctl.gait.swing_fraction
    for f in range(2):  # the left foot swings at phase [0, w), the right half a cycle later
        standing = (ph + 0.5 * f) % 1.0 >= w
        first = np.argmax(standing)  # a stance foot keeps its offset until it lifts again
        run = first + np.argmax(~standing[first:]) if (~standing[first:]).any() else len(ph)
        assert np.array_equal(off[first:run, :, f], np.broadcast_to(off[first, :, f],
                                                                   off[first:run, :, f].shape))
        swing_x = off[~standing, 0, f, 0]  # it gets there along the swing, not at once
        assert np.any((swing_x > 1e-4) & (swing_x < swing_x.max() - 1e-4))
    size = np.linalg.norm(dv, axis=1, keepdims=True)
    shrunk = dv * (size - DEADBAND_MPS) / size  # the dead band taken off |Δv|
    want_x = np.minimum(shrunk[:, 0] / omega, REACH_X_M)
    np.testing.assert_allclose(layer.offset[:, :, 0], np.stack([want_x, want_x], 1),
                               atol=1e-12)
    assert layer.offset[0, :, 1] == pytest.approx([0.0, 0.0], abs=1e-12)
    assert layer.offset[1, 0, 1] == pytest.approx(min(shrunk[1, 1] / omega, 0.08))  # outward
    assert layer.offset[1, 1, 1] == pytest.approx(0.01)  # right foot: inward, clipped
    assert np.abs(outs[-1]).max() > 0.05  # the legs really moved


def test_the_layer_gives_the_engine_on_every_row_bit_for_bit(problem):
    """The layer runs the engine only on the rows whose feet it moves (or whose phase or
    command is not finite): its output is, bit for bit, the action plus the engine with the
    feet moved less without on every row, the former formulation; rows that move no foot keep
    their action exactly, and a NaN command makes the row NaN as in the ONNX layer."""
    from evomotion.studies.humanoid_omniwalk.omni_gait import targets

    ctl = problem.ctl
    names = [*ctl.sim.observe.names, "torso_velocity:x", "torso_velocity:y"]
    vcols = [len(names) - 2, len(names) - 1]
    n = 5
    layer = CaptureStep(ctl, names, n, 1.0, velocity=vcols, sway=np.zeros((ctl.window, 2)))
    rng = np.random.default_rng(4)
    obs = np.zeros((n, len(names)))
    command = rng.uniform(-0.3, 0.3, (n, 3))
    obs[:, [names.index(f"command:{i}") for i in range(3)]] = command
    # velocity offsets from the command: none, 0.5 forward, 0.4 right, one inside the dead
    # band (0.14 m/s), one beside a NaN turn
    obs[:, vcols] = command[:, :2] + [[0.0, 0.0], [0.5, 0.0], [0.0, -0.4], [0.1, 0.1],
                                      [0.6, 0.3]]
    obs[4, names.index("command:2")] = np.nan
    action = rng.normal(scale=0.05, size=(n, ctl.columns.size))
    moved_rows = set()
    for c in range(ctl.window + 3):
        phase = c * ctl.control_dt / ctl.gait.period_s
        obs[:, names.index("phase:sin")] = math.sin(2 * math.pi * phase)
        obs[:, names.index("phase:cos")] = math.cos(2 * math.pi * phase)
        out = layer(np.arange(n), obs, action)
        off = layer.offset.copy()
        ph, cmd = layer.phase(obs), obs[:, layer.ic]
        want = action + (targets(ctl.gait, ph, cmd, off)
                         - targets(ctl.gait, ph, cmd, np.zeros_like(off)))[:, ctl.columns]
        assert np.array_equal(out[:4].view(np.uint64), want[:4].view(np.uint64))
        assert np.isnan(out[4]).any() and np.array_equal(np.isnan(out), np.isnan(want))
        still = ~(off[:4] != 0).any(axis=(1, 2))
        assert np.array_equal(out[:4][still], action[:4][still])
        moved_rows |= set(np.flatnonzero(~still).tolist())
    assert moved_rows == {1, 2}  # the offsets beyond the dead band moved a foot, no other


def test_a_run_with_the_capture_step_is_reproducible_and_independent_of_neighbours(problem):
    """Each row's episodes carry their own layer state: a row scores the same alone and
    beside others, twice; the layer changes the score against the same problem without it."""
    x0 = problem.initial_population(None, np.random.default_rng(0))
    g = x0 + 0.002 * np.random.default_rng(2).standard_normal((3, problem.genome.dim))
    rows = policy_rows(g, np.zeros(problem.obs_dim), np.ones(problem.obs_dim), 11, 2)
    ev = problem.evaluate(rows)
    np.testing.assert_array_equal(problem.evaluate(rows).fitness, ev.fitness)
    np.testing.assert_array_equal(problem.evaluate(rows[1:2]).fitness, ev.fitness[1:2])
    plain = OmniWalkProblem(OmniWalkConfig(duration_s=3.0, threads=1))
    assert not np.array_equal(plain.evaluate(rows).fitness, ev.fitness)


def test_the_capture_step_is_refused_off_the_nao_and_out_of_range():
    with pytest.raises(InputError, match="problem.capture_gain"):
        OmniWalkConfig(capture_gain=-0.1).validate()
    with pytest.raises(InputError, match="problem.capture_gain: the capture step needs"):
        OmniWalkProblem(OmniWalkConfig(robot="op3", capture_gain=0.5, threads=1))


def test_a_run_with_the_capture_step_exports_it_and_its_player_runs_it(tmp_path):
    """policy.json records the layer; naoqi/ gets capture_step.py; the policy player (play,
    walk-to, the live walk) runs policy + layer as the simulator does: pushed after its
    warm-up, its targets are the numpy policy + layer's on its observations (1e-9), and they
    differ from the policy's alone; compare runs it too and says so."""
    import json

    import mujoco

    from evomotion.core.policies.export import read_policy_npz
    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study
    from evomotion.sim.policy_player import PolicyPlayer
    from evomotion.sim.state import STATE_SPEC
    from evomotion.studies import get_study
    from evomotion.studies.humanoid_omniwalk.compare import compare, compare_command

    s = get_study("humanoid-walk")
    out = tmp_path / "run"
    tiny = ("problem.duration_s=1.0", "problem.eval_episodes=1", "problem.episodes=1",
            "problem.threads=1", "algorithm.pop_size=4", "algorithm.top_directions=0",
            "run.generations=1", "run.videos=false", "problem.capture_gain=0.7")
    cfg = resolve_config(s, None, list(tiny))
    run_study(s, cfg, out, quiet=True)
    info = json.loads((out / "policy.json").read_text())
    assert info["layers"]["capture_step"]["gain"] == 0.7
    naoqi = json.loads((out / "naoqi" / "policy.json").read_text())
    assert naoqi["capture_step"]["gain"] == 0.7 and (out / "naoqi" / "capture_step.py").is_file()
    layer_file = (out / "capture_step.py").read_bytes()
    assert layer_file == (out / "naoqi" / "capture_step.py").read_bytes()
    assert "+ capture_step.py: walk the NAO" in (out / "log.txt").read_text()
    problem = OmniWalkProblem(cfg.problem)
    model = problem.robot.model
    player = PolicyPlayer(out, model, {"left": "left_floor", "right": "right_floor"})
    pol = read_policy_npz(out / "policy.npz")
    ref = CaptureStep(problem.ctl, list(problem.obs_names), 1, 0.7)
    d = mujoco.MjData(model)
    mujoco.mj_setState(model, d, problem.ctl.state0, STATE_SPEC)
    mujoco.mj_forward(model, d)
    player.start(d)
    torso = model.body("torso").id
    moved = 0.0
    for c in range(125):  # 2.5 s; a push of 2.5 N s from behind at 1.6-1.7 s
        d.xfrc_applied[torso, 0] = 25.0 if 80 <= c < 85 else 0.0
        ctrl = player.targets(d, [0.1, 0.0, 0.0])
        obs = player.observe(d)  # what targets() read (the command ramped first)
        act = pol.spec.act(pol.params[None], obs[None], pol.obs_mean, pol.obs_std)
        want = ref(np.array([0]), obs[None], act)[0]
        np.testing.assert_allclose(ctrl[player.columns], np.clip(
            player.nominal_driven + want, player.lower, player.upper), rtol=0, atol=1e-9)
        moved = max(moved, float(np.abs(want - act[0]).max()))
        d.ctrl[:] = ctrl
        for _ in range(player.control_steps):
            mujoco.mj_step(model, d)
    assert moved > 0.01
    # a run folder's record from before the layer's settings were written is refused
    old = json.loads((out / "policy.json").read_text())
    old["layers"]["capture_step"] = {"gain": 0.7, "com_height_m": 0.25}
    (out / "policy.json").write_text(json.dumps(old))
    with pytest.raises(InputError, match="key 'layers.capture_step': an object with"):
        PolicyPlayer(out, mujoco.MjModel.from_xml_string("<mujoco/>"))
    (out / "policy.json").write_text(json.dumps(info))
    # compare runs it (the run's gain, or --capture-gain over it) and says so
    text = compare_command(out, worlds=1, duration_s=1.0)
    assert ", capture step gain 0.7" in text and "| walk engine (the start) + capture step" in text
    res = json.loads(compare_command(out, worlds=1, duration_s=1.0, json_out=True,
                                     capture_gain=0.0))
    assert res["capture_gain"] == 0.0
    with pytest.raises(InputError, match="--capture-gain"):
        compare(out, worlds=1, duration_s=1.0, capture_gain=-1.0)


def test_the_online_layer_waits_its_warm_up_cycles(problem):
    """Learning the sway online, the layer moves no foot in its first WARMUP_CYCLES cycles,
    however large the velocity it reads (an oracle column of 1 m/s)."""
    from evomotion.studies.humanoid_omniwalk.capture_step import WARMUP_CYCLES

    ctl = problem.ctl
    names = [*ctl.sim.observe.names, "torso_velocity:x", "torso_velocity:y"]
    layer = CaptureStep(ctl, names, 1, 1.0, velocity=[len(names) - 2, len(names) - 1])
    obs = np.zeros((1, len(names)))
    obs[0, -2] = 1.0
    action = np.zeros((1, ctl.columns.size))
    moved = []
    for c in range((WARMUP_CYCLES + 1) * ctl.window):
        phase = c * ctl.control_dt / ctl.gait.period_s
        obs[0, names.index("phase:sin")] = math.sin(2 * math.pi * phase)
        obs[0, names.index("phase:cos")] = math.cos(2 * math.pi * phase)
        moved.append(np.abs(layer(np.arange(1), obs, action)).max())
    assert max(moved[:WARMUP_CYCLES * ctl.window]) == 0.0
    assert max(moved[WARMUP_CYCLES * ctl.window:]) > 0.01


@pytest.mark.parametrize("speed", [0.1, 0.5])
def test_the_sway_is_learnt_only_from_calm_steps(problem, speed):
    """The online sway table follows a velocity offset below CALIBRATION_GATE_MPS (0.1 m/s:
    learnt, so it moves no foot after the warm-up) and ignores one above it (0.5 m/s: the
    table stays 0, the offset is a push and moves the feet)."""
    from evomotion.studies.humanoid_omniwalk.capture_step import CALIBRATION_GATE_MPS

    assert 0.1 < CALIBRATION_GATE_MPS < 0.5
    ctl = problem.ctl
    names = [*ctl.sim.observe.names, "torso_velocity:x", "torso_velocity:y"]
    layer = CaptureStep(ctl, names, 1, 1.0, velocity=[len(names) - 2, len(names) - 1],
                        deadband_mps=0.0)
    obs = np.zeros((1, len(names)))
    obs[0, -2] = speed
    action = np.zeros((1, ctl.columns.size))
    moved = 0.0
    for c in range(12 * ctl.window):
        phase = c * ctl.control_dt / ctl.gait.period_s
        obs[0, names.index("phase:sin")] = math.sin(2 * math.pi * phase)
        obs[0, names.index("phase:cos")] = math.cos(2 * math.pi * phase)
        out = layer(np.arange(1), obs, action)
        if c >= 10 * ctl.window:
            moved = max(moved, float(np.abs(out).max()))
    if speed < CALIBRATION_GATE_MPS:
        np.testing.assert_allclose(layer.sway[0, :, 0], speed, atol=0.002)
        assert moved < 0.005
    else:
        assert np.array_equal(layer.sway, np.zeros_like(layer.sway)) and moved > 0.02


def test_leg_odometry_needs_the_hip_yaw_pitch_rate_while_turning(problem):
    """Turning at 1 rad/s in place (the fitted engine, nominal world): the odometry's mean
    forward error with the hip yaw-pitch's rate is well below that without it (3.4 against
    7.1 cm/s here; a review measured 4.4 against 8.3 on another gait)."""
    ctl = problem.ctl
    sim, names, true_cols = _reading(ctl)
    x, od = ctl.initial_params(), problem.obs_dim
    layer = CaptureStep(ctl, names, 1, 0.0)
    errors: list[tuple[float, float]] = []

    def policy(rows, obs):
        act = problem.policy.act(x[None], obs[:, :od], np.zeros((1, od)), np.ones((1, od)))
        phase = layer.phase(obs)
        true = obs[0, true_cols]
        with_rate = layer.velocity_of(rows, obs, phase)[0]
        without = layer.odometry(obs, phase, layer.hip_yaw_pitch[rows], np.zeros(1))[0]
        errors.append((abs(with_rate[0] - true[0]), abs(without[0] - true[0])))
        return layer(rows, obs, act)

    res = sim.run(policy, 1, int(2.5 / problem.dt), commands=np.array([(0.0, 0.0, 1.0)]),
                  initial_state=ctl.state0)
    sim.close()
    assert not res.fell[0]
    e = np.array(errors[2 * ctl.window:])
    assert e[:, 0].mean() < 0.7 * e[:, 1].mean()
