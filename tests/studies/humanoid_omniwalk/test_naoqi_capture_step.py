"""The NAOqi runner's capture step (``naoqi/capture_step.py``, standard library only) moves the
feet as the study's numpy layer does: on the observation stream of a pushed simulated walk the
two give the same actions to 1e-9, and the whole runner, fed a simulated walk through a fake
NAOqi, sends the numpy policy + layer's targets on its own observations to 1e-6 (its joint
velocities are finite differences, as on the NAO). Also under Python 2.7 where this machine
has one. No NAO is here: the robot's sensors, timing and walking are not checked."""

from __future__ import annotations

import ast
import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).parent.parent / "humanoid_balance"))
sys.path.insert(0, str(Path(__file__).parents[2] / "sim" / "robots" / "nao"))
import fake_naoqi  # noqa: E402
from pushed_walk import fuzzed, pushed_walk  # noqa: E402
from test_naoqi_policy_export import _NotPy2, _python2  # noqa: E402
from test_naoqi_runner import PERIOD_S, _frame, _load_runner, _Offset  # noqa: E402

from evomotion.core.policies.export import export_policy, read_policy_npz  # noqa: E402
from evomotion.errors import InputError  # noqa: E402
from evomotion.sim.robots.nao.policy_export import (  # noqa: E402
    CAPTURE_STEP,
    runner_source,
    write_naoqi_policy,
)
from evomotion.studies.humanoid_omniwalk.artifacts import (  # noqa: E402
    capture_step_record,
    policy_info,
)
from evomotion.studies.humanoid_omniwalk.capture_step import CaptureStep  # noqa: E402
from evomotion.studies.humanoid_omniwalk.problem import (  # noqa: E402
    OmniWalkProblem,
)

COMMAND = [0.25, -0.05, 0.4]


def _module(folder: Path | None = None):
    path = (folder / CAPTURE_STEP if folder is not None else
            Path(__file__).parents[3] / "src/evomotion/sim/robots/nao/naoqi_capture_step.py")
    spec = importlib.util.spec_from_file_location("capture_step_for_tests", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def walk():
    return pushed_walk()


def _layers(p, record):
    names = list(p.obs_names)
    info = policy_info(p)
    std = _module().CaptureStep(record, names, info["joints"], info["nominal_rad"],
                                p.ctl.control_dt)
    ref = CaptureStep(p.ctl, names, 1, record["gain"])
    return std, ref


def test_the_standard_library_layer_moves_the_feet_as_numpy_does(walk):
    p, obs, action = walk
    std, ref = _layers(p, capture_step_record(p.ctl, 1.5))
    rows = np.array([0])
    moved = 0.0
    for o, a in zip(obs, action, strict=True):
        want = ref(rows, o[None], a[None])[0]
        got = np.array(std(list(map(float, o)), list(map(float, a))))
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)
        moved = max(moved, float(np.abs(want - a).max()))
    assert moved > 0.02  # the push moved a foot (the comparison is not of zeros)


def test_the_runner_sends_the_numpy_policy_and_layers_targets(walk, tmp_path, monkeypatch):
    p, obs, _ = walk
    m = p.robot.model
    rng = np.random.default_rng(2)
    params = p.ctl.initial_params()
    mean, std = rng.normal(0, 0.05, p.obs_dim), rng.uniform(0.8, 1.2, p.obs_dim)
    export_policy(tmp_path, p.policy, params, mean, std, ("npz",))
    info = policy_info(p)
    record = capture_step_record(p.ctl, 1.5)
    write_naoqi_policy(tmp_path / "naoqi", read_policy_npz(tmp_path / "policy.npz"),
                       p.obs_names, info["joints"], info["nominal_rad"], info["lower_rad"],
                       info["upper_rad"], PERIOD_S, info["phase_period_s"],
                       info["nominal_pose_all_actuators"], command_ramp_s=p.cfg.ramp_s,
                       capture_step=record)
    folder = tmp_path / "naoqi"
    assert (folder / CAPTURE_STEP).read_text() == runner_source(CAPTURE_STEP)
    # ALMemory frames from a simulated pushed walk (the states of the episode above)
    p2 = OmniWalkProblem(p.cfg)
    _, res, _ = p2.play(params[None], mean[None], std[None], np.array([3]))
    contact = [p2.sim.observe.slices["foot_contact"].start + i for i in range(2)]
    joints = [m.joint(int(m.actuator_trnid[c, 0])).name for c in p2.robot.columns]
    C = obs.shape[0]
    frames = [_frame(m, joints, res.states[0, c], obs[c][contact]) for c in range(C)]
    p2.sim.close()
    clock = fake_naoqi.FakeClock(50.0)
    naoqi = fake_naoqi.install(clock=clock)
    monkeypatch.setitem(sys.modules, "naoqi", naoqi)
    mod = _load_runner(folder)
    rec = json.loads((folder / "policy.json").read_text())
    runner = mod.Runner(rec, naoqi.memory, naoqi.dcm, naoqi.motion, command=COMMAND,
                        clock=clock, sleep=clock.sleep)
    seen = []
    observe = runner.observe

    def spy(values, t):
        seen.append(observe(values, t))
        return seen[-1]

    runner.observe = spy
    runner.observe.keys = observe.keys  # type: ignore[attr-defined]
    runner.start()
    naoqi.memory.stream = frames
    naoqi.memory.clock, naoqi.memory.period_s = _Offset(clock, 50.0), PERIOD_S
    steps, late = runner.run(C * PERIOD_S - 1e-9, PERIOD_S)
    assert (steps, late) == (C, 0)
    sent = np.array([v for _, v in naoqi.dcm.sent])
    ref = CaptureStep(p.ctl, list(p.obs_names), 1, 1.5)
    o = np.array(seen)
    want = []
    for k in range(C):
        act = p.policy.act(params[None], o[k][None], mean[None], std[None])
        want.append(ref(np.array([0]), o[k][None], act)[0])
    targets = np.clip(np.array(info["nominal_rad"]) + np.array(want), info["lower_rad"],
                      info["upper_rad"])
    np.testing.assert_allclose(sent, targets, rtol=0, atol=1e-6)
    plain = np.clip(np.array(info["nominal_rad"]) + np.array(
        [p.policy.act(params[None], x[None], mean[None], std[None])[0] for x in o]),
        info["lower_rad"], info["upper_rad"])
    assert np.abs(sent - plain).max() > 0.01  # the layer acted on the robot's stream


def test_the_layer_is_python_2_7_safe_and_standard_library_only():
    src = runner_source(CAPTURE_STEP)
    tree = ast.parse(src)
    v = _NotPy2()
    v.visit(tree)
    assert v.found == [] and src.isascii()
    imported = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import)
                for a in n.names}
    imported |= {n.module.split(".")[0] for n in ast.walk(tree)
                 if isinstance(n, ast.ImportFrom) and n.module}
    assert imported == {"__future__", "math"}


_PY2 = """
import json, sys
sys.path.insert(0, sys.argv[1])
import policy_runner
cs = policy_runner._capture_step_module()  # by imp on Python 2.7
d = json.load(open(sys.argv[2]))
layer = cs.CaptureStep(d["record"], d["names"], d["joints"], d["nominal"], d["dt"])
print(json.dumps([layer(o, a) for o, a in zip(d["obs"], d["action"])]))
"""


def test_python_2_7_runs_the_layer_like_python_3(walk, tmp_path):
    py2 = _python2()
    if py2 is None:
        pytest.skip("no Python 2.7 on this machine")
    p, obs, action = walk
    (tmp_path / CAPTURE_STEP).write_text(runner_source(CAPTURE_STEP))
    (tmp_path / "policy_runner.py").write_text(runner_source())
    info = policy_info(p)
    d = {"record": capture_step_record(p.ctl, 1.5), "names": list(p.obs_names),
         "joints": info["joints"], "nominal": info["nominal_rad"], "dt": p.ctl.control_dt,
         "obs": obs.tolist(), "action": action.tolist()}
    (tmp_path / "in.json").write_text(json.dumps(d))
    out = subprocess.run([py2, "-c", _PY2, str(tmp_path), str(tmp_path / "in.json")],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    std = _module(tmp_path).CaptureStep(d["record"], d["names"], d["joints"], d["nominal"],
                                        d["dt"])
    want = [std(list(map(float, o)), list(map(float, a))) for o, a in zip(obs, action)]
    np.testing.assert_allclose(json.loads(out.stdout), want, rtol=0, atol=1e-12)


def test_export_refuses_a_capture_step_without_its_observations(walk, tmp_path):
    p, _, _ = walk
    export_policy(tmp_path, p.policy, p.ctl.initial_params(), np.zeros(p.obs_dim),
                  np.ones(p.obs_dim), ("npz",))
    info = policy_info(p)
    names = [n.replace("gyro:z", "roll_pitch:roll") for n in p.obs_names]
    with pytest.raises(InputError, match="capture step reads gyro:z"):
        write_naoqi_policy(tmp_path / "naoqi", read_policy_npz(tmp_path / "policy.npz"),
                           names, info["joints"], info["nominal_rad"], info["lower_rad"],
                           info["upper_rad"], PERIOD_S, info["phase_period_s"],
                           capture_step=capture_step_record(p.ctl, 1.0))
    assert not (tmp_path / "naoqi").exists()


def test_the_runner_needs_the_layer_file_and_the_policys_period(walk, tmp_path, monkeypatch,
                                                                capsys):
    p, _, _ = walk
    export_policy(tmp_path, p.policy, p.ctl.initial_params(), np.zeros(p.obs_dim),
                  np.ones(p.obs_dim), ("npz",))
    info = policy_info(p)
    folder = tmp_path / "naoqi"
    write_naoqi_policy(folder, read_policy_npz(tmp_path / "policy.npz"), p.obs_names,
                       info["joints"], info["nominal_rad"], info["lower_rad"],
                       info["upper_rad"], PERIOD_S, info["phase_period_s"],
                       info["nominal_pose_all_actuators"],
                       capture_step=capture_step_record(p.ctl, 1.0))
    naoqi = fake_naoqi.install()
    monkeypatch.setitem(sys.modules, "naoqi", naoqi)
    mod = _load_runner(folder)
    js = str(folder / "policy.json")
    assert mod.main([js, "--command", "0.1,0,0", "--period-ms", "10", "--dry-run"]) == 1
    assert "capture step runs at the policy's period, 20 ms" in capsys.readouterr().err
    (folder / CAPTURE_STEP).unlink()
    assert mod.main([js, "--command", "0.1,0,0", "--dry-run", "--seconds", "0.02"]) == 1
    assert "capture_step.py is missing" in capsys.readouterr().err


_JUNK = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6),
                  st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=5),
                  st.lists(st.floats(-10, 10), max_size=3), st.dictionaries(st.text(max_size=3),
                                                                            st.integers(),
                                                                            max_size=2))


@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_a_bad_record_is_one_value_error_line(walk, data):
    """Any key of the record replaced by junk: the layer either builds and acts or raises one
    ValueError naming the key (the runner prints it, the player turns it into one line)."""
    p, obs, action = walk
    record = json.loads(json.dumps(capture_step_record(p.ctl, 1.0)))
    path = data.draw(st.sampled_from(
        [(k,) for k in record] + [("gait", k) for k in record["gait"]]
        + [("geometry", k) for k in record["geometry"]] + [("ranges", "LKneePitch")]
        + [("ranges", "X"), ("gait", "X"), ("X",)]))  # extra keys too
    junk = data.draw(_JUNK)
    target = record
    for k in path[:-1]:
        target = target[k]
    target[path[-1]] = junk
    info = policy_info(p)
    mod = _module()
    try:
        layer = mod.CaptureStep(record, list(p.obs_names), info["joints"],
                                info["nominal_rad"], p.ctl.control_dt)
    except ValueError as e:
        assert str(e).startswith("capture_step: ") and "\n" not in str(e)
        return
    for o, a in zip(obs[:40], action[:40], strict=True):
        assert len(layer(list(map(float, o)), list(map(float, a)))) == len(a)


def test_the_layers_agree_on_a_fuzzed_stream(walk):
    """The pushed walk's stream made harder (noisy joint velocities, jittered phase, random
    contacts and commands, gains 0.5-3): the standard-library and numpy layers still agree to
    1e-9 at every step (a review found clips, the lift-off blend and the phase bin's rounding
    unexercised by the plain stream)."""
    p, obs, action = walk
    names = list(p.obs_names)
    rng = np.random.default_rng(7)
    for gain in (0.5, 3.0):
        std, ref = _layers(p, capture_step_record(p.ctl, gain))
        for k in range(4):  # the stream four times over: the sway table learnt, then pushed
            o = fuzzed(names, obs, rng, k)
            for x, a in zip(o, action, strict=True):
                want = ref(np.array([0]), x[None], a[None])[0]
                np.testing.assert_allclose(std(x.tolist(), a.tolist()), want, rtol=0,
                                           atol=1e-9)


def test_a_nan_reading_or_action_does_not_stop_the_layer(walk):
    """A NaN in the gyro, an uncounted foot's joint velocity or the policy's action for one
    step: both layers give finite actions again at the next step, alike."""
    p, obs, action = walk
    names = list(p.obs_names)
    std, ref = _layers(p, capture_step_record(p.ctl, 1.5))
    bad = {80: ("obs", names.index("gyro:x")), 90: ("obs", names.index("joint_vel:LKneePitch")),
           100: ("action", 0)}
    for k, (x, a) in enumerate(zip(obs, action, strict=True)):
        x, a = x.copy(), a.copy()
        if k in bad:
            where, i = bad[k]
            (x if where == "obs" else a)[i] = np.nan
        want = ref(np.array([0]), x[None], a[None])[0]
        got = np.array(std(x.tolist(), a.tolist()))
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)
        if k not in bad:
            assert np.isfinite(want).all(), k
