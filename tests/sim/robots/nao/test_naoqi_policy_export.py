"""The NAOqi export of closed-loop policies: the runner is Python-2.7-safe (checked on its
syntax tree, and run under a Python 2.7 where this machine has one), its gravity from roll and
pitch is the simulator's, joint velocities are a finite difference, and a policy the NAO
cannot run is refused in one line."""

from __future__ import annotations

import ast
import glob
import importlib.util
import json
import math
import os
import shutil
import subprocess

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.core.policies import make_policy
from evomotion.core.policies.export import ExportedPolicy
from evomotion.errors import InputError
from evomotion.sim.observations import ObservationBuilder, ObservationSpec
from evomotion.sim.robots import load_robot
from evomotion.sim.robots.nao import policy_export
from evomotion.sim.robots.nao.policy_export import (
    PITCH_KEY,
    ROLL_KEY,
    fsr_key,
    joint_key,
    naoqi_policy_record,
    runner_source,
    write_naoqi_policy,
)
from evomotion.sim.state import QPOS_OFFSET, STATE_SPEC

RUNNER = os.path.join(os.path.dirname(policy_export.__file__), "policy_runner.py")
NAMES = ["joint_pos:LHipPitch", "joint_pos:LKneePitch", "joint_vel:LHipPitch", "gyro:x",
         "gyro:y", "gravity:x", "gravity:y", "gravity:z", "roll_pitch:roll",
         "roll_pitch:pitch", "foot_contact:left", "foot_contact:right", "phase:sin",
         "phase:cos", "command:0"]
JOINTS = ["LHipPitch", "LKneePitch", "LAnklePitch"]


def _runner_module():
    spec = importlib.util.spec_from_file_location("policy_runner_under_test", RUNNER)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _policy(kind: str = "mlp", names=NAMES, seed: int = 0, harmonics: int = 3
            ) -> ExportedPolicy:
    rng = np.random.default_rng(seed)
    o, a = len(names), len(JOINTS)
    opts: dict = {"hidden": (5, 4)} if kind == "mlp" else {}
    if kind == "structured":
        opts = {"harmonics": harmonics, "phase_columns": (names.index("phase:sin"),
                                                          names.index("phase:cos"))}
    spec = make_policy(kind, o, a, scale=0.3, low=-0.2 * np.ones(a), high=np.full(a, np.inf),
                       clip_obs=3.0, **opts)
    return ExportedPolicy(spec, rng.normal(0, 0.5, spec.n_params), rng.normal(0, 0.1, o),
                          rng.uniform(0.1, 1.0, o))


def _record(policy=None, names=NAMES):
    return naoqi_policy_record(policy or _policy(), names, JOINTS, [-0.5, 1.0, -0.5],
                               [-1.5, 0.0, -1.2], [0.4, 2.1, 0.8], 0.02, 0.5)


class _NotPy2(ast.NodeVisitor):
    """Collects the constructs Python 2.7 cannot parse or runs differently."""

    def __init__(self) -> None:
        self.found: list[str] = []

    def _add(self, node, what):
        self.found.append(f"line {getattr(node, 'lineno', '?')}: {what}")

    def visit_JoinedStr(self, node):  # noqa: N802
        self._add(node, "f-string")

    def visit_AnnAssign(self, node):  # noqa: N802
        self._add(node, "variable annotation")

    def visit_Nonlocal(self, node):  # noqa: N802
        self._add(node, "nonlocal")

    def visit_YieldFrom(self, node):  # noqa: N802
        self._add(node, "yield from")

    def visit_AsyncFunctionDef(self, node):  # noqa: N802
        self._add(node, "async def")

    def visit_Await(self, node):  # noqa: N802
        self._add(node, "await")

    def visit_MatMult(self, node):  # noqa: N802
        self._add(node, "@ (matmul)")

    def visit_NamedExpr(self, node):  # noqa: N802
        self._add(node, ":= (walrus)")

    def visit_Starred(self, node):  # noqa: N802
        self._add(node, "starred expression (unpacking generalisations)")

    def visit_FunctionDef(self, node):  # noqa: N802
        a = node.args
        if a.kwonlyargs or a.posonlyargs:
            self._add(node, "keyword-only or positional-only arguments")
        if node.returns is not None or any(x.annotation is not None for x in
                                           a.args + a.kwonlyargs):
            self._add(node, "annotation")
        self.generic_visit(node)

    def visit_ClassDef(self, node):  # noqa: N802
        if not node.bases:
            self._add(node, "old-style class (no base)")
        self.generic_visit(node)

    def visit_ImportFrom(self, node):  # noqa: N802
        if node.module == "__future__" and any(n.name == "annotations" for n in node.names):
            self._add(node, "from __future__ import annotations")
        self.generic_visit(node)

    def visit_Raise(self, node):  # noqa: N802
        if node.cause is not None:
            self._add(node, "raise ... from")
        self.generic_visit(node)


def test_the_runner_is_python_2_7_safe_and_standard_library_only():
    src = runner_source()
    tree = ast.parse(src)
    v = _NotPy2()
    v.visit(tree)
    assert v.found == []
    future = [n for n in tree.body if isinstance(n, ast.ImportFrom) and n.module == "__future__"]
    assert future and {"print_function", "division"} <= {a.name for a in future[0].names}
    imported = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import)
                for a in n.names}
    imported |= {n.module.split(".")[0] for n in ast.walk(tree)
                 if isinstance(n, ast.ImportFrom) and n.module}
    # importlib (Python 3) or imp (2.7) load capture_step.py beside it
    assert imported == {"__future__", "argparse", "json", "math", "os", "sys", "time", "naoqi",
                        "importlib", "imp"}
    assert src.isascii()  # Python 2 reads the file with its coding line; keep it plain


def test_the_checker_catches_python_3_only_code():
    for bad in ("x = f'{1}'", "def f(*, a): pass", "def f(a: int): pass", "x: int = 1",
                "def f():\n    yield from g()", "a @ b", "class A: pass",
                "raise ValueError() from None", "async def f(): pass"):
        v = _NotPy2()
        v.visit(ast.parse(bad))
        assert v.found, bad


def _python2() -> str | None:
    cands = [shutil.which("python2.7"), shutil.which("python2")]
    cands += sorted(glob.glob(os.path.expanduser("~/.pyenv/versions/2.7*/bin/python2.7")))
    for c in cands:
        if not c:
            continue
        try:
            out = subprocess.run([c, "-c", "import sys; print(sys.version_info[0])"],
                                 capture_output=True, text=True, timeout=20)
        except (OSError, subprocess.TimeoutExpired):
            continue
        if out.returncode == 0 and out.stdout.strip() == "2":
            return c
    return None


_PY2_SCRIPT = """
import json, sys
sys.path.insert(0, sys.argv[1])
import policy_runner as r
record = json.load(open(sys.argv[2]))
obs = r.Observer(record, [0.25])
pol = r.Policy(record)
out = []
for t, frame in json.load(open(sys.argv[3])):
    x = obs([frame[k] for k in obs.keys], t)
    out.append([x, pol(x)])
print(json.dumps(out))
"""


@pytest.mark.parametrize("kind", ["mlp", "structured"])
def test_python_2_7_runs_the_runner_like_python_3(kind, tmp_path):
    py2 = _python2()
    if py2 is None:
        pytest.skip("no Python 2.7 on this machine")
    paths = write_naoqi_policy(tmp_path / "naoqi", _policy(kind), NAMES, JOINTS,
                               [-0.5, 1.0, -0.5], [-1.5, 0.0, -1.2], [0.4, 2.1, 0.8], 0.02,
                               0.5)
    record = json.loads(paths["json"].read_text())
    mod = _runner_module()
    obs3 = mod.Observer(record, [0.25])
    rng = np.random.default_rng(1)
    frames = [[0.02 * i, {k: float(rng.normal(0, 0.5)) for k in obs3.keys}] for i in range(5)]
    (tmp_path / "frames.json").write_text(json.dumps(frames))
    out = subprocess.run([py2, "-c", _PY2_SCRIPT, str(tmp_path / "naoqi"), str(paths["json"]),
                          str(tmp_path / "frames.json")], capture_output=True, text=True,
                         timeout=60)
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    pol3 = mod.Policy(record)
    for (t, frame), (x2, a2) in zip(frames, got, strict=True):
        x3 = obs3([frame[k] for k in obs3.keys], t)
        np.testing.assert_allclose(x2, x3, rtol=0, atol=1e-12)
        np.testing.assert_allclose(a2, pol3(x3), rtol=0, atol=1e-12)
    help_out = subprocess.run([py2, str(paths["runner"]), "--help"], capture_output=True,
                              text=True, timeout=60)
    assert help_out.returncode == 0 and "--dry-run" in help_out.stdout


def test_the_runner_policy_is_the_exported_policy():
    mod = _runner_module()
    for kind in ("linear", "mlp", "structured"):
        p = _policy(kind, seed=3)
        runner_policy = mod.Policy(json.loads(json.dumps(_jsonable(_record(p)))))
        obs = np.random.default_rng(2).normal(0, 2.0, (20, len(NAMES)))
        want = p.spec.act(np.repeat(p.params[None], len(obs), 0), obs, p.obs_mean, p.obs_std)
        got = np.array([runner_policy(list(x)) for x in obs])
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)


def _jsonable(record):
    from evomotion.outfile import _json_default, json_safe

    return json.loads(json.dumps(json_safe(record), default=_json_default))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-1, 1, allow_nan=False), min_size=4, max_size=4).filter(
    lambda q: sum(v * v for v in q) > 1e-3))
def test_gravity_from_roll_pitch_is_the_simulators(q):
    robot = load_robot("nao")
    m = robot.model
    quat = np.array(q) / np.linalg.norm(q)
    state = np.zeros(mujoco.mj_stateSize(m, STATE_SPEC))
    state[QPOS_OFFSET + 3:QPOS_OFFSET + 7] = quat
    b = ObservationBuilder(ObservationSpec(("gravity", "roll_pitch")), robot)
    obs = b(state[None])[0]
    g = _runner_module().gravity(obs[3], obs[4])
    # 1e-7: at pitch ±90° asin(1 - eps) loses half the digits (~sqrt(2 eps) = 2e-8)
    np.testing.assert_allclose(g, obs[:3], rtol=0, atol=1e-7)


def test_joint_velocity_is_a_finite_difference_over_the_measured_period():
    record = _jsonable(_record())
    obs = _runner_module().Observer(record, [0.25])
    col = NAMES.index("joint_vel:LHipPitch")
    frame = {k: 0.0 for k in obs.keys}
    frame[joint_key("LHipPitch")] = -0.5
    assert obs([frame[k] for k in obs.keys], 0.0)[col] == 0.0  # no previous reading
    frame[joint_key("LHipPitch")] = -0.47
    v = obs([frame[k] for k in obs.keys], 0.012)[col]  # a late step: 12 ms measured
    assert v == pytest.approx(0.03 / 0.012, rel=1e-12)
    assert record["approximated"] == {"joint_vel": policy_export.APPROXIMATED["joint_vel"]}


def test_sensor_layout_contacts_phase_and_one_read():
    record = _jsonable(_record())
    obs = _runner_module().Observer(record, [0.25])
    assert len(obs.keys) == len(set(obs.keys))
    assert {ROLL_KEY, PITCH_KEY, fsr_key("LFoot"), fsr_key("RFoot")} <= set(obs.keys)
    assert fsr_key("LFoot") == "Device/SubDeviceList/LFoot/FSR/TotalWeight/Sensor/Value"
    frame = {k: 0.0 for k in obs.keys}
    frame[fsr_key("LFoot")] = 2.5
    frame[fsr_key("RFoot")] = 0.1
    x = obs([frame[k] for k in obs.keys], 0.125)
    got = dict(zip(NAMES, x, strict=True))
    assert (got["foot_contact:left"], got["foot_contact:right"]) == (1.0, 0.0)
    assert got["phase:sin"] == pytest.approx(1.0) and abs(got["phase:cos"]) < 1e-12
    assert got["command:0"] == 0.25
    with pytest.raises(ValueError, match="command"):
        _runner_module().Observer(record, [])


@pytest.mark.parametrize("names, msg", [
    (["torso_velocity:x", "torso_height", "gyro:x"],
     "reads torso_height, torso_velocity, which no NAO sensor"),
    (["torso_height", "gyro:x", "gyro:y"], "reads torso_height"),
    (["gyro:w", "gyro:x", "gyro:y"], "'gyro:w' has no NAO source"),
])
def test_unmeasurable_channels_are_refused_in_one_line(names, msg, tmp_path):
    with pytest.raises(InputError, match=msg) as e:
        write_naoqi_policy(tmp_path / "naoqi", _policy("linear", names), names, JOINTS,
                           [0.0] * 3, [-1.0] * 3, [1.0] * 3, 0.02)
    assert "\n" not in str(e.value) and not (tmp_path / "naoqi").exists()


def test_bad_joints_and_periods_are_refused_in_one_line():
    p = _policy("linear")
    with pytest.raises(InputError, match="one hip yaw-pitch motor"):
        naoqi_policy_record(p, NAMES, ["LHipPitch", "RHipYawPitch", "LKneePitch"], [0.0] * 3,
                            [-1.0] * 3, [1.0] * 3, 0.02)
    with pytest.raises(InputError, match="10-20 ms"):
        naoqi_policy_record(p, NAMES, JOINTS, [0.0] * 3, [-1.0] * 3, [1.0] * 3, 0.05)
    with pytest.raises(InputError, match="3 joints"):
        naoqi_policy_record(p, NAMES, JOINTS[:2], [0.0] * 2, [-1.0] * 2, [1.0] * 2, 0.02)


def test_the_nao_has_the_capability_and_the_files_are_written(tmp_path):
    mod = load_robot("nao").capability("naoqi_policy", "test")
    assert mod is policy_export
    paths = write_naoqi_policy(tmp_path / "naoqi", _policy(), NAMES, JOINTS, [-0.5, 1.0, -0.5],
                               [-1.5, 0.0, -1.2], [0.4, 2.1, 0.8], 0.02, 0.5)
    assert paths["runner"].read_text() == runner_source()
    record = json.loads(paths["json"].read_text())
    assert record["format"] == policy_export.FORMAT and record["joints"] == JOINTS
    assert record["action_high"] == [None] * 3 and record["clip_obs"] == 3.0
    assert [layer["activation"] for layer in record["layers"]] == ["tanh"] * 3
    assert not math.isnan(record["control_period_s"])
