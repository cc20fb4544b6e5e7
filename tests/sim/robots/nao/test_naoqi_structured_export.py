"""The NAOqi export of structured policies (a Fourier tape of the raw phase plus linear
feedback): ``policy.json`` holds their own record, the runner's forward pass is ``policy.py``'s
(and the training code's) to 1e-12, and bad records are refused in one line at both ends."""

from __future__ import annotations

import importlib.util
import json
import os

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.core.policies import make_policy, standalone
from evomotion.core.policies.export import ExportedPolicy, policy_arrays
from evomotion.errors import InputError
from evomotion.outfile import _json_default, json_safe
from evomotion.sim.robots.nao import policy_export
from evomotion.sim.robots.nao.policy_export import (
    naoqi_policy_record,
    structured_record,
    write_naoqi_policy,
)

RUNNER = os.path.join(os.path.dirname(policy_export.__file__), "policy_runner.py")
NAMES = ["joint_pos:LHipPitch", "joint_pos:LKneePitch", "gyro:x", "gyro:y", "phase:sin",
         "gravity:x", "gravity:z", "phase:cos", "foot_contact:left", "foot_contact:right"]
JOINTS = ["LHipPitch", "LKneePitch", "LAnklePitch"]
SIN, COS = NAMES.index("phase:sin"), NAMES.index("phase:cos")
BOUNDS = ([-0.5, 1.0, -0.5], [-1.5, 0.0, -1.2], [0.4, 2.1, 0.8])


def _runner():
    spec = importlib.util.spec_from_file_location("structured_policy_runner", RUNNER)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _policy(seed: int = 0, harmonics: int = 2, cols=(SIN, COS), clip_obs: float = 2.0,
            command_feedback: bool = False) -> ExportedPolicy:
    rng = np.random.default_rng(seed)
    o, a = len(NAMES), len(JOINTS)
    # with command feedback: two columns stand in for a command (the runner reads them raw)
    extra = {"command_columns": (0, 5), "command_feedback": True} if command_feedback else {}
    spec = make_policy("structured", o, a, scale=rng.uniform(0.1, 0.5, a),
                       offset=rng.normal(0, 0.1, a), low=np.array([-0.3, -np.inf, -0.4]),
                       high=np.array([0.3, 0.5, np.inf]), clip_obs=clip_obs,
                       harmonics=harmonics, phase_columns=cols, **extra)
    return ExportedPolicy(spec, rng.normal(0, 0.5, spec.n_params), rng.normal(0, 0.1, o),
                          rng.uniform(0.1, 1.0, o))


def _command_names() -> list[str]:
    """NAMES with columns 0 and 5 as the command (the NAOqi export checks the names)."""
    names = list(NAMES)
    names[0], names[5] = "command:0", "command:1"
    return names


def _record(p: ExportedPolicy, names=NAMES, phase_period_s: float = 0.5) -> dict:
    record = naoqi_policy_record(p, names, JOINTS, *BOUNDS, 0.02, phase_period_s)
    return json.loads(json.dumps(json_safe(record), default=_json_default))  # as on the robot


def _observations(rng: np.random.Generator, n: int) -> np.ndarray:
    """Raw observations: half with the phase on the unit circle (as the clock gives), half
    anywhere (the recurrence is evaluated as written either way)."""
    obs = rng.normal(0, 2.0, (n, len(NAMES)))
    phi = rng.uniform(0, 2 * np.pi, n // 2)
    obs[: n // 2, SIN], obs[: n // 2, COS] = np.sin(phi), np.cos(phi)
    return obs


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**31), st.integers(0, 5), st.sampled_from([2.0, float("inf")]),
       st.booleans())
def test_the_runners_structured_forward_is_policy_py(seed, harmonics, clip_obs, fed_back):
    p = _policy(seed, harmonics, clip_obs=clip_obs, command_feedback=fed_back)
    runner_policy = _runner().Policy(_record(p, _command_names() if fed_back else NAMES))
    policy_py = standalone.Policy(policy_arrays(p.spec, p.params, p.obs_mean, p.obs_std))
    obs = _observations(np.random.default_rng(seed), 16)
    got = np.array([runner_policy(list(x)) for x in obs])
    want = policy_py(obs)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    assert np.array_equal(got, want)  # in fact the same bits: the same order of operations
    trained = p.spec.act(np.repeat(p.params[None], len(obs), 0), obs, p.obs_mean, p.obs_std)
    np.testing.assert_allclose(got, trained, rtol=0, atol=1e-12)
    assert np.ptp(got, axis=0).max() > 1e-3  # not stuck at a bound


def test_the_tape_reads_the_raw_phase_and_the_gains_the_rest():
    """A hand-made policy: tape y_j = a_j0 + b_j2 cos 2phi, one gain on gyro:x; the runner's
    action is that, whatever the phase columns' normaliser says."""
    p = _policy(1, harmonics=2, clip_obs=float("inf"))
    a, o = len(JOINTS), len(NAMES)
    tape = np.zeros((a, 5))
    tape[:, 0], tape[:, 4] = 0.1, 1.0
    gain = np.zeros((a, o - 2))
    gain[0, 2] = 0.5  # x without the phase columns: column 2 is gyro:x
    params = np.concatenate([tape.ravel(), gain.ravel()])
    p = ExportedPolicy(p.spec, params, p.obs_mean, p.obs_std)
    runner_policy = _runner().Policy(_record(p))
    obs = np.zeros(o)
    phi = 0.3
    obs[SIN], obs[COS], obs[2] = np.sin(phi), np.cos(phi), 0.7
    y = 0.1 + np.cos(2 * phi) + np.array([0.5 * (0.7 - p.obs_mean[2]) / p.obs_std[2], 0, 0])
    want = np.clip(p.spec.offset + p.spec.scale * y, p.spec.low, p.spec.high)
    np.testing.assert_allclose(runner_policy(list(obs)), want, rtol=0, atol=1e-12)


def test_the_record_is_the_structured_policys(tmp_path):
    p = _policy(2, harmonics=3)
    paths = write_naoqi_policy(tmp_path / "naoqi", p, NAMES, JOINTS, *BOUNDS, 0.02, 0.5)
    record = json.loads(paths["json"].read_text())
    assert record["kind"] == "structured" and "layers" not in record
    assert record["harmonics"] == 3 and record["phase_columns"] == [SIN, COS]
    (tape, _), (gain, _) = p.spec.unflatten(p.params)
    np.testing.assert_array_equal(record["tape_coef"], tape)
    np.testing.assert_array_equal(record["feedback_gain"], gain)
    assert np.shape(record["tape_coef"]) == (3, 7) and np.shape(record["feedback_gain"]) == (3, 8)
    assert record["action_low"][1] is None and record["clip_obs"] == 2.0
    sources = {c["name"]: c["source"] for c in record["observation"]}
    assert (sources["phase:sin"], sources["phase:cos"]) == ("phase_sin", "phase_cos")


def _arrays(**change):
    p = _policy(3)
    arrays = policy_arrays(p.spec, p.params, p.obs_mean, p.obs_std)
    arrays.update(change)
    return arrays


@pytest.mark.parametrize("make, msg", [
    (lambda: naoqi_policy_record(_policy(cols=(0, 1)), NAMES, JOINTS, *BOUNDS, 0.02, 0.5),
     r"phase columns \[0, 1\] must be the observation's phase:sin and phase:cos"),
    (lambda: naoqi_policy_record(_policy(cols=(COS, SIN)), NAMES, JOINTS, *BOUNDS, 0.02, 0.5),
     "must be the observation's phase:sin and phase:cos"),
    (lambda: naoqi_policy_record(ExportedPolicy(_policy().spec, np.zeros(5), np.zeros(10),
                                                np.ones(10)), NAMES, JOINTS, *BOUNDS, 0.02, 0.5),
     "params must be"),
    (lambda: naoqi_policy_record(_policy(), NAMES, JOINTS, *BOUNDS, 0.02, 0.0),
     "reads phase; phase_period_s must be > 0"),
    (lambda: structured_record(_arrays(tape_coef=np.zeros((3, 4))), NAMES),
     r"tape_coef must be finite numbers of shape \(3, 5\), got shape \(3, 4\)"),
    (lambda: structured_record(_arrays(feedback_gain=np.zeros((2, 8))), NAMES),
     r"feedback_gain must be finite numbers of shape \(3, 8\)"),
    (lambda: structured_record(_arrays(tape_coef=np.full((3, 5), np.nan)), NAMES),
     "tape_coef must be finite"),
    (lambda: structured_record(_arrays(), ["gyro:z" if n == "phase:cos" else n for n in NAMES]),
     "phase columns"),
    (lambda: structured_record(_arrays(), NAMES + ["gyro:z"]),
     r"feedback_gain must be finite numbers of shape \(3, 9\)"),
])
def test_bad_structured_records_are_one_line(make, msg):
    with pytest.raises(InputError, match=msg) as e:
        make()
    assert "\n" not in str(e.value) and str(e.value).startswith("NAOqi export:")


def test_nothing_is_written_for_a_bad_structured_policy(tmp_path):
    with pytest.raises(InputError):
        write_naoqi_policy(tmp_path / "naoqi", _policy(cols=(0, 1)), NAMES, JOINTS, *BOUNDS,
                           0.02, 0.5)
    assert not (tmp_path / "naoqi").exists()


@pytest.mark.parametrize("change, msg", [
    ({"tape_coef": [[0.0] * 5] * 2}, "tape_coef must be 3 x 5 numbers"),
    ({"tape_coef": [[0.0] * 4] * 3}, "tape_coef must be 3 x 5 numbers"),
    ({"feedback_gain": [[0.0] * 9] * 3}, "feedback_gain must be 3 x 8 numbers"),
    ({"phase_columns": [4, 4]}, "phase_columns"),
    ({"phase_columns": [4, 10]}, "phase_columns"),
    ({"harmonics": -1}, "harmonics"),
    ({"kind": "cpg"}, "a 'cpg' policy; this runner runs"),
])
def test_the_runner_refuses_a_bad_structured_record_in_one_line(change, msg):
    record = _record(_policy(4))
    record.update(change)
    with pytest.raises(ValueError, match=msg) as e:
        _runner().Policy(record)
    assert "\n" not in str(e.value)


def test_the_runner_refuses_a_phase_without_a_period():
    record = _record(_policy(5))
    record["phase_period_s"] = 0.0
    with pytest.raises(ValueError, match="phase_period_s must be > 0"):
        _runner().Observer(record)
