"""The walk's capture step as a stateful ONNX graph (``capture_step_onnx``) and the walk
controller in one ONNX model (``controller.onnx``), run by onnxruntime's CPU provider with the
state fed back: on a pushed simulated walk, on a fuzzed stream (noisy velocities, jittered
phase, random contacts and commands, gains 0.5 and 3) and with NaN readings, they give the
numpy layer's (and the numpy policy + layer's) actions to 1e-6 rad and its state to 1e-9 (the
graph takes float32 observations and actions and returns a float32 action; the numpy layer is
fed the same float32 values; the graph computes in float64). A mutated setting (the gain
initializer, the thigh's length, the calibration rate, the dead band) fails the comparison."""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from pushed_walk import fuzzed, pushed_walk  # noqa: E402

ort = pytest.importorskip("onnxruntime")
onnx = pytest.importorskip("onnx")

from evomotion.sim.robots.nao.capture_step_onnx import (  # noqa: E402
    capture_step_model,
    controller_model,
    initial_state,
    state_layout,
)
from evomotion.studies.humanoid_omniwalk.artifacts import (  # noqa: E402
    CONTROLLER_ONNX,
    capture_step_record,
    policy_info,
    write_policy,
)
from evomotion.studies.humanoid_omniwalk.capture_step import (  # noqa: E402
    WARMUP_CYCLES,
    CaptureStep,
)

TOL = 1e-6  # rad: the float32 action out (its rounding ~1e-8 here) with a margin
STATE_TOL = 1e-9
ROW = np.array([0])


@pytest.fixture(scope="module")
def walk():
    return pushed_walk()


def _session(model):
    return ort.InferenceSession(model.SerializeToString(), providers=["CPUExecutionProvider"])


def _model(p, record):
    info = policy_info(p)
    return capture_step_model(record, list(p.obs_names), info["joints"], info["nominal_rad"],
                              p.ctl.control_dt)


def _run(p, record, obs, action, model=None, ref=None, state=None, check=True):
    """Both layers over the stream (float32 values into both; ``ref``, the numpy layer, and
    ``state``, the ONNX layer's, may carry on from an earlier stream): (largest |ONNX − numpy|
    action difference, largest |layer − policy| after the warm-up, the numpy layer, the ONNX
    state)."""
    ref = ref or CaptureStep(p.ctl, list(p.obs_names), 1, record["gain"])
    sess = _session(model or _model(p, record))
    state = initial_state(record) if state is None else state
    worst = moved = 0.0
    for k, (o, a) in enumerate(zip(obs.astype(np.float32), action.astype(np.float32),
                                   strict=True)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # numpy's bin of a NaN phase
            want = ref(ROW, o[None].astype(float), a[None].astype(float))[0]
        got, state = sess.run(None, {"observation": o[None], "action": a[None],
                                     "state_in": state})
        if check:
            np.testing.assert_array_equal(np.isnan(got[0]), np.isnan(want), err_msg=str(k))
        worst = max(worst, float(np.nanmax(np.abs(got[0] - want), initial=0.0)))
        if ref.steps[0] > WARMUP_CYCLES * ref.bins:
            moved = max(moved, float(np.nanmax(np.abs(want - a), initial=0.0)))
    return worst, moved, ref, state


def _assert_same_state(record, ref, state, tol=STATE_TOL):
    """The ONNX state (flat, module doc's layout) equals the numpy layer's (the hip
    yaw-pitch's rate to ``tol / dt``: the float32 action's rounding over a control period)."""
    at = {k: slice(*v) for k, v in state_layout(record).items()}
    s = state[0]
    np.testing.assert_allclose(s[at["sway"]], ref.sway[0].ravel(), rtol=0, atol=tol)
    assert s[at["steps"]][0] == ref.steps[0]
    np.testing.assert_allclose(s[at["offset"]], ref.offset[0].ravel(), rtol=0, atol=tol)
    np.testing.assert_allclose(s[at["lift_off"]], ref.lift_off[0].ravel(), rtol=0, atol=tol)
    np.testing.assert_array_equal(s[at["swinging"]], ref.swinging[0])
    nominal = ref.ctl.nominal[ref.ctl.columns[ref.hyp_col]]
    np.testing.assert_allclose(nominal + s[at["hip_yaw_pitch"]], ref.hip_yaw_pitch, rtol=0,
                               atol=tol)
    np.testing.assert_allclose(s[at["hip_yaw_pitch_rate"]], ref.hip_yaw_pitch_rate, rtol=0,
                               atol=tol / ref.ctl.control_dt)


def test_the_onnx_layer_moves_the_feet_as_numpy_does(walk):
    p, obs, action = walk
    record = capture_step_record(p.ctl, 1.5)
    assert len(obs) > (WARMUP_CYCLES + 2) * p.ctl.window  # two cycles after the warm-up
    worst, moved, ref, state = _run(p, record, obs, action)
    assert worst <= TOL, worst
    assert moved > 1e-3  # the layer moved a foot after its warm-up: not a comparison of zeros
    _assert_same_state(record, ref, state)


def test_the_onnx_layer_agrees_on_a_fuzzed_stream(walk):
    """test_naoqi_capture_step.py's fuzzed stream: the pushed walk four times over with noisy
    joint velocities, jittered phase, random contacts and commands, at gains 0.5 and 3."""
    p, obs, action = walk
    names = list(p.obs_names)
    rng = np.random.default_rng(7)
    for gain in (0.5, 3.0):
        record, ref, state, worst, moved = capture_step_record(p.ctl, gain), None, None, 0.0, 0.0
        model = _model(p, record)
        for k in range(4):
            o = fuzzed(names, obs, rng, k)
            w, m, ref, state = _run(p, record, o, action, model, ref, state)
            worst, moved = max(worst, w), max(moved, m)
        assert worst <= TOL, (gain, worst)
        assert moved > 1e-3
        _assert_same_state(record, ref, state)


def test_the_warm_up_ends_at_the_same_step(walk):
    """A gyro spike on the last call before the layer acts (its step count ``warmup · bins``)
    moves no foot in either layer; the same spike on the next call, the first that acts, does
    (so a layer acting one call early would differ; the spike at eight phases of the stream)."""
    p, obs, action = walk
    record, gyro = capture_step_record(p.ctl, 1.5), list(p.obs_names).index("gyro:y")
    model, last = _model(p, record), WARMUP_CYCLES * p.ctl.window - 1  # 0-based call
    late = 0.0
    for shift in range(0, p.ctl.window, 3):
        for at in (last, last + 1):
            o = obs[shift:shift + at + 1].copy()
            o[at, gyro] = 8.0
            worst, moved, _, _ = _run(p, record, o, action[shift:shift + at + 1], model)
            assert worst <= TOL, (shift, at, worst)
            late = max(late, moved)  # 0 where at == last: no call after the warm-up
    assert late > 1e-3  # a spike on the first acting call moves a foot


def test_a_record_whose_settings_all_differ(walk, monkeypatch):
    """The record's gate, rate, warm-up, reach and dead band each unlike the others (in the
    default the gate and the dead band are both 0.2 m/s, so a graph reading one for the other
    would pass): numpy's constants patched to the same values, the fuzzed velocities."""
    from evomotion.studies.humanoid_omniwalk import capture_step as cs

    for name, value in (("CALIBRATION_GATE_MPS", 0.35), ("CALIBRATION_RATE", 0.45),
                        ("WARMUP_CYCLES", 2), ("REACH_X_M", 0.08), ("OUT_Y_M", 0.06),
                        ("IN_Y_M", 0.02), ("DEADBAND_MPS", 0.15)):
        monkeypatch.setattr(cs, name, value)
    p, obs, action = walk
    record = capture_step_record(p.ctl, 1.5)
    assert (record["calibration_gate_mps"], record["deadband_mps"]) == (0.35, 0.15)
    o = obs.copy()
    vel = [i for i, n in enumerate(p.obs_names) if n.startswith("joint_vel:")]
    o[:, vel] += np.random.default_rng(5).normal(0, 1.0, (len(o), len(vel)))
    ref = CaptureStep(p.ctl, list(p.obs_names), 1, 1.5, deadband_mps=0.15)
    worst, moved, ref, state = _run(p, record, o, action, ref=ref)
    assert worst <= TOL, worst
    assert moved > 1e-3
    _assert_same_state(record, ref, state)


def test_nan_readings_behave_as_in_the_numpy_layer(walk):
    """After the warm-up: a NaN gyro, a NaN joint velocity and angle, every sensor NaN, a whole
    NaN row (clock and command too) and a NaN hip yaw-pitch action, each for one step: the
    same actions (NaN where numpy's are) and the same state; finite again at the next step."""
    p, obs, action = walk
    names = list(p.obs_names)
    sensors = [i for i, n in enumerate(names) if n.split(":")[0] in
               ("joint_pos", "joint_vel", "gyro", "foot_contact")]
    bad = {80: [names.index("gyro:x")], 84: [names.index("joint_vel:LKneePitch")],
           85: [names.index("joint_vel:RHipPitch")], 90: [names.index("joint_pos:RHipRoll")],
           95: sensors, 100: list(range(len(names)))}
    o, a = obs.copy(), action.copy()
    for k, cols in bad.items():
        o[k, cols] = np.nan
    a[105, 0] = np.nan  # LHipYawPitch: the motor holds its target
    record = capture_step_record(p.ctl, 1.5)
    worst, moved, ref, state = _run(p, record, o, a)
    assert worst <= TOL and moved > 1e-3
    _assert_same_state(record, ref, state)
    sess, st = _session(_model(p, record)), initial_state(record)
    for k in range(len(o)):
        got, st = sess.run(None, {"observation": o[k:k + 1].astype(np.float32),
                                  "action": a[k:k + 1].astype(np.float32), "state_in": st})
        assert np.isfinite(st).all() and (k in bad or k == 105 or np.isfinite(got).all()), k


def test_rows_are_robots(walk):
    """A batch of two robots (one with a biased joint velocity): each row as numpy's."""
    p, obs, action = walk
    record = capture_step_record(p.ctl, 1.5)
    sess, state = _session(_model(p, record)), initial_state(record, 2)
    ref = CaptureStep(p.ctl, list(p.obs_names), 2, 1.5)
    biased = obs.copy()
    biased[:, list(p.obs_names).index("joint_vel:LHipPitch")] += 0.7
    for k in range(len(obs)):
        o = np.stack([obs[k], biased[k]]).astype(np.float32)
        a = np.stack([action[k], action[k]]).astype(np.float32)
        want = ref(np.array([0, 1]), o.astype(float), a.astype(float))
        got, state = sess.run(None, {"observation": o, "action": a, "state_in": state})
        np.testing.assert_allclose(got, want, rtol=0, atol=TOL)
    assert np.abs(state[0] - state[1]).max() > 1e-3


def test_a_bad_record_or_policy_is_one_value_error(walk):
    p, _, _ = walk
    info, record = policy_info(p), capture_step_record(p.ctl, 1.5)
    names = [n.replace("gyro:z", "roll_pitch:roll") for n in p.obs_names]
    with pytest.raises(ValueError, match="capture_step: it reads observation 'gyro:z'"):
        capture_step_model(record, names, info["joints"], info["nominal_rad"], 0.02)
    with pytest.raises(ValueError, match="capture_step: gain"):
        capture_step_model({**record, "gain": -1.0}, list(p.obs_names), info["joints"],
                           info["nominal_rad"], 0.02)
    with pytest.raises(ValueError, match="capture_step: control_period_s 0.0"):
        capture_step_model(record, list(p.obs_names), info["joints"], info["nominal_rad"], 0.0)
    with pytest.raises(ValueError, match="LHipYawPitch"):
        capture_step_model(record, list(p.obs_names), info["joints"][1:],
                           info["nominal_rad"][1:], 0.02)


@pytest.mark.parametrize("mutation", ["gain initializer", "thigh_m", "calibration_rate",
                                      "deadband_mps"])
def test_a_mutated_graph_fails_the_comparison(walk, mutation):
    p, obs, action = walk
    record = capture_step_record(p.ctl, 1.5)
    wrong = json.loads(json.dumps(record))
    if mutation == "thigh_m":
        wrong["geometry"]["thigh_m"] *= 1.01
    elif mutation != "gain initializer":
        wrong[mutation] *= 0.7
    model = _model(p, wrong)
    if mutation == "gain initializer":
        init = next(t for t in model.graph.initializer if t.name == "capture_step/gain")
        init.CopyFrom(onnx.numpy_helper.from_array(np.array(1.6), init.name))
    worst, _, _, _ = _run(p, record, obs, action, model, check=False)
    assert worst > 100 * TOL, worst


def test_controller_onnx_is_the_numpy_policy_and_layer(walk):
    p, obs, _ = walk
    rng = np.random.default_rng(2)
    params = p.ctl.initial_params()
    mean, std = rng.normal(0, 0.05, p.obs_dim), rng.uniform(0.8, 1.2, p.obs_dim)
    record, info = capture_step_record(p.ctl, 1.5), policy_info(p)
    model = controller_model(p.policy, params, mean, std, record, list(p.obs_names),
                             info["joints"], info["nominal_rad"], p.ctl.control_dt)
    assert [i.name for i in model.graph.input] == ["observation", "state_in"]
    assert [o.name for o in model.graph.output] == ["action", "state_out"]
    sess, state = _session(model), initial_state(record)
    ref = CaptureStep(p.ctl, list(p.obs_names), 1, 1.5)
    worst = moved = 0.0
    for x in obs.astype(np.float32):
        act = p.policy.act(params[None], x[None].astype(float), mean[None], std[None])
        want = ref(ROW, x[None].astype(float), act)[0]
        got, state = sess.run(None, {"observation": x[None], "state_in": state})
        worst = max(worst, float(np.abs(got[0] - want).max()))
        moved = max(moved, float(np.abs(want - act[0]).max()))
    assert worst <= TOL, worst
    assert moved > 1e-3
    # the float32 policy's actions (numpy's are float64) move the hip yaw-pitch's state
    _assert_same_state(record, ref, state, tol=TOL)


def _ctx(p, out_dir, logs):
    rng = np.random.default_rng(3)
    best = SimpleNamespace(best_cost=-1.0, best_x=p.ctl.initial_params(),
                           best_obs_mean=rng.normal(0, 0.05, p.obs_dim),
                           best_obs_std=rng.uniform(0.8, 1.2, p.obs_dim), valid=None)
    return SimpleNamespace(problem=p, state=best, out_dir=out_dir, cache={}, log=logs.append)


def test_a_run_folder_has_a_controller_onnx_that_loads(walk, tmp_path, monkeypatch):
    p, obs, _ = walk
    logs: list[str] = []
    ctx = _ctx(p, tmp_path, logs)
    write_policy(ctx)
    assert (tmp_path / "capture_step.py").is_file() and (tmp_path / "policy.onnx").is_file()
    model = onnx.load(tmp_path / CONTROLLER_ONNX)
    onnx.checker.check_model(model)
    info = json.loads((tmp_path / "policy.json").read_text())["layers"]["capture_step"]
    record = {k: v for k, v in info.items() if k not in ("file", "note", "controller_onnx")}
    assert info["controller_onnx"]["file"] == CONTROLLER_ONNX
    assert info["controller_onnx"]["state_layout"] == state_layout(record)
    assert json.loads({m.key: m.value for m in model.metadata_props}[
        "capture_step_state_layout"]) == state_layout(record)
    sess, state = _session(model), initial_state(record)
    policy, ref = _session(onnx.load(tmp_path / "policy.onnx")), _session(_model(p, record))
    ref_state = initial_state(record)
    for x in obs[:100].astype(np.float32):  # controller.onnx = policy.onnx, then the layer
        got, state = sess.run(None, {"observation": x[None], "state_in": state})
        act = policy.run(None, {"observation": x[None]})[0]
        want, ref_state = ref.run(None, {"observation": x[None], "action": act,
                                         "state_in": ref_state})
        np.testing.assert_array_equal(got, want)
    assert not logs
    # without the onnx extra: no controller.onnx, one note
    (tmp_path / CONTROLLER_ONNX).unlink()
    monkeypatch.setitem(sys.modules, "onnx", None)
    write_policy(ctx)
    write_policy(ctx)
    assert not (tmp_path / CONTROLLER_ONNX).exists()
    layer = json.loads((tmp_path / "policy.json").read_text())["layers"]["capture_step"]
    assert "controller_onnx" not in layer and layer["file"] == "capture_step.py"
    assert logs.count("note: controller.onnx not written (pip install 'evomotion[onnx]')") == 1
