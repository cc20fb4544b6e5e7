"""Exported policies agree with the numpy forward: policy.npz read back exactly, the numpy-only
policy.py run with ``python -I`` from a folder holding only it and policy.npz (so it needs
nothing of evomotion) to 1e-12, onnxruntime (float32) to 1e-5."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from evomotion.core.policies import POLICIES, LinearSpec, MLPSpec, StructuredSpec
from evomotion.core.policies.export import (
    export_policy,
    read_policy_npz,
    standalone_source,
    write_policy_npz,
)
from evomotion.errors import FileFormatError
from evomotion.outfile import WriteError

#: runs ./policy.py as ``__main__`` with evomotion made unimportable (installed or not)
BLOCKED = ("import runpy, sys; sys.modules['evomotion'] = None; "
           "sys.argv = ['policy.py', *sys.argv[1:]]; runpy.run_path('policy.py', "
           "run_name='__main__')")

SPECS = {
    "linear": LinearSpec(7, 3, scale=0.5, offset=[0.1, -0.2, 0.3], low=-1.0, high=[1, 2, 0.5],
                         clip_obs=5.0),
    "linear-bias-unclipped": LinearSpec(7, 3, bias=True),
    "mlp": MLPSpec(7, 3, hidden=(16, 8), scale=[1.0, 2.0, 0.5], offset=[0.0, 0.5, -0.5],
                   low=[-0.8, -1.0, -1.0], high=[0.8, 2.5, 0.0], clip_obs=3.0),
    "structured": StructuredSpec(7, 3, phase_columns=(5, 2), harmonics=3, scale=[1.0, 2.0, 0.5],
                                 offset=[0.0, 0.5, -0.5], low=[-0.8, -1.0, -1.0],
                                 high=[0.8, 2.5, 0.0], clip_obs=3.0),
    "structured-tape-only": StructuredSpec(2, 2, phase_columns=(1, 0), harmonics=0),
    "structured-commanded": StructuredSpec(7, 3, phase_columns=(5, 2), harmonics=2,
                                           command_columns=(6, 0, 3), clip_obs=4.0),
    "structured-command-feedback": StructuredSpec(7, 3, phase_columns=(5, 2), harmonics=2,
                                                  command_columns=(6, 3),
                                                  command_feedback=True, clip_obs=4.0),
}


def test_every_kind_is_exported() -> None:
    assert {type(s) for s in SPECS.values()} == set(POLICIES.values())


def _policy(spec, seed=0):
    rng = np.random.default_rng(seed)
    params = (spec.initial_params(rng) if isinstance(spec, MLPSpec)
              else rng.normal(scale=0.5, size=spec.n_params))
    return params, rng.normal(size=spec.obs_dim), rng.uniform(0.2, 3.0, size=spec.obs_dim)


@pytest.mark.parametrize("name", sorted(SPECS))
def test_numpy_standalone_and_onnx_agree(name, tmp_path) -> None:
    spec = SPECS[name]
    params, mean, std = _policy(spec)
    paths = export_policy(tmp_path, spec, params, mean, std)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["policy.npz", "policy.onnx",
                                                          "policy.py"]
    rng = np.random.default_rng(1)
    obs = (mean + rng.normal(size=(64, spec.obs_dim)) * std * 4).astype(np.float32)
    ref = spec.act(np.broadcast_to(params, (64, spec.n_params)), obs.astype(np.float64), mean,
                   std)
    assert (ref == spec.low).any() or (ref == spec.high).any() or spec.low[0] == -np.inf

    alone = tmp_path / "alone"
    alone.mkdir()
    for f in ("policy.py", "policy.npz"):
        (alone / f).write_bytes(paths[f.split(".")[1]].read_bytes())
    text = "\n".join(",".join(repr(float(v)) for v in row) for row in obs.astype(np.float64))
    run = subprocess.run([sys.executable, "-I", "-c", BLOCKED, "policy.npz"], cwd=alone,
                         input=text, capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    out = np.array([[float(v) for v in line.split(",")] for line in run.stdout.splitlines()])
    np.testing.assert_allclose(out, ref, rtol=0, atol=1e-12)
    one = subprocess.run([sys.executable, "-I", "policy.py", "--obs", text.splitlines()[0]],
                         cwd=alone, capture_output=True, text=True, timeout=60)
    assert one.returncode == 0, one.stderr
    np.testing.assert_allclose([float(v) for v in one.stdout.split(",")], ref[0], atol=1e-12)

    ort = pytest.importorskip("onnxruntime")
    session = ort.InferenceSession(str(paths["onnx"]), providers=["CPUExecutionProvider"])
    assert [i.name for i in session.get_inputs()] == ["observation"]
    assert [o.name for o in session.get_outputs()] == ["action"]
    (got,) = session.run(["action"], {"observation": obs})
    assert got.dtype == np.float32 and got.shape == ref.shape
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-5 * max(1.0, np.abs(ref).max()))


def test_standalone_imports_only_numpy_and_the_standard_library() -> None:
    src = standalone_source()
    imports = {line.split()[1].split(".")[0] for line in src.splitlines()
               if line.startswith(("import ", "from "))}
    assert imports <= {"__future__", "math", "sys", "pathlib", "numpy"}, imports
    assert "evomotion" not in src.replace("evomotion policy", "").replace(
        "written by evomotion", "")


@pytest.mark.parametrize("name", sorted(SPECS))
def test_npz_round_trip_is_exact(name, tmp_path) -> None:
    spec = SPECS[name]
    params, mean, std = _policy(spec, seed=5)
    write_policy_npz(tmp_path / "policy.npz", spec, params, mean, std)
    back = read_policy_npz(tmp_path / "policy.npz")
    assert type(back.spec) is type(spec) and back.spec.n_params == spec.n_params
    assert np.array_equal(back.params, params)
    assert np.array_equal(back.obs_mean, mean) and np.array_equal(back.obs_std, std)
    for key in ("scale", "offset", "low", "high"):
        assert np.array_equal(getattr(back.spec, key), getattr(spec, key))
    assert back.spec.clip_obs == spec.clip_obs
    if isinstance(spec, MLPSpec):
        assert isinstance(back.spec, MLPSpec) and back.spec.hidden == spec.hidden
    elif isinstance(spec, StructuredSpec):
        assert isinstance(back.spec, StructuredSpec)
        assert back.spec.harmonics == spec.harmonics
        assert back.spec.phase_columns == spec.phase_columns
    else:
        assert isinstance(back.spec, LinearSpec) and back.spec.bias == spec.bias


def _corrupt(tmp_path, name, change, kind="mlp"):
    spec = SPECS[kind]
    params, mean, std = _policy(spec)
    path = write_policy_npz(tmp_path / "p.npz", spec, params, mean, std)
    with np.load(path) as f:
        arrays = {k: f[k] for k in f.files}
    change(arrays)
    np.savez(tmp_path / name, **arrays)
    return tmp_path / name


@pytest.mark.parametrize(("change", "message"), [
    (lambda a: a.pop("obs_std"), "'obs_std' is missing"),
    (lambda a: a.pop("layer1_bias"), "'layer1_bias' is missing"),
    (lambda a: a.update(format_version=np.array(2)), "'format_version' is 2"),
    (lambda a: a.update(kind=np.array("rnn")), "'kind' must be one of linear, mlp, structured"),
    (lambda a: a.update(obs_mean=a["obs_mean"][:-1]), "'obs_mean' must be numbers of shape"),
    (lambda a: a.update(layer1_weight=a["layer1_weight"][:, :-1]), "'layer1_weight' has 15"),
    (lambda a: a["layer0_weight"].__setitem__((0, 0), np.nan), "'layer0_weight' holds NaN"),
    (lambda a: a["obs_std"].__setitem__(0, np.inf), "'obs_std' holds a non-finite number"),
    (lambda a: a["obs_std"].__setitem__(0, 0.0), "'obs_std' must be > 0"),
    (lambda a: a.update(output_tanh=np.array(False)), "'output_tanh' must be 1"),
    (lambda a: a.update(extra=np.zeros(2)), "'extra' is not a key"),
    (lambda a: a.update(action_low=np.full(3, 9.0)), "low must not exceed high"),
])
def test_bad_files_are_one_line_errors(tmp_path, change, message) -> None:
    path = _corrupt(tmp_path, "bad.npz", change)
    with pytest.raises(FileFormatError) as e:
        read_policy_npz(path)
    assert message in str(e.value) and str(path) in str(e.value) and "\n" not in str(e.value)


def test_not_a_zip_and_bad_targets_are_one_line(tmp_path) -> None:
    (tmp_path / "x.npz").write_bytes(b"PK\x03\x04 not really")
    with pytest.raises(FileFormatError, match="not a zip archive"):
        read_policy_npz(tmp_path / "x.npz")
    spec = SPECS["linear"]
    params, mean, std = _policy(spec)
    with pytest.raises(WriteError, match="does not exist"):
        export_policy(tmp_path / "missing", spec, params, mean, std, ("npz",))
    with pytest.raises(ValueError, match="unknown policy format 'tflite'"):
        export_policy(tmp_path, spec, params, mean, std, ("tflite",))
    with pytest.raises(ValueError, match="params must be"):
        export_policy(tmp_path, spec, params[:-1], mean, std)
    assert not list(tmp_path.glob("policy.*"))


@pytest.mark.parametrize(("change", "message"), [
    (lambda a: a.pop("tape_coef"), "'tape_coef' is missing"),
    (lambda a: a.pop("phase_columns"), "'phase_columns' is missing"),
    (lambda a: a.update(harmonics=np.array(2)), "'tape_coef' must be a matrix [a, 5]"),
    (lambda a: a.update(harmonics=np.array(65)), "'harmonics' is 65, expected 0..64"),
    (lambda a: a.update(harmonics=np.array(1.5)), "'harmonics' must be one whole number"),
    (lambda a: a.update(phase_columns=np.array([2, 2])), "two different columns in 0..6"),
    (lambda a: a.update(phase_columns=np.array([0, 7])), "two different columns in 0..6"),
    (lambda a: a.update(phase_columns=np.array([0.0, 1.0])), "'phase_columns' must be two"),
    (lambda a: a.update(phase_columns=np.array([1, 2, 3])), "'phase_columns' must be two"),
    (lambda a: a.update(feedback_gain=a["feedback_gain"][:2]), "'feedback_gain' must be a"),
    (lambda a: a.update(feedback_gain=a["feedback_gain"][:, :-1]), "'obs_mean' must be"),
    (lambda a: a["tape_coef"].__setitem__((0, 0), np.inf), "'tape_coef' holds a non-finite"),
    (lambda a: a["feedback_gain"].__setitem__((0, 0), np.nan), "'feedback_gain' holds NaN"),
    (lambda a: a.update(n_layers=np.array(1)), "'n_layers' is not a key"),
    (lambda a: a.update(command_gain=np.zeros((2, 5))), "'command_gain' must be a matrix"),
    (lambda a: a.update(output_tanh=np.array(True)), "'output_tanh' must be 0"),
])
def test_bad_structured_files_are_one_line_errors(tmp_path, change, message) -> None:
    path = _corrupt(tmp_path, "bad.npz", change, "structured")
    with pytest.raises(FileFormatError) as e:
        read_policy_npz(path)
    assert message in str(e.value) and str(path) in str(e.value) and "\n" not in str(e.value)


def test_structured_policy_py_is_exactly_the_numpy_policy(tmp_path) -> None:
    """On observations whose phase columns lie on the unit circle (as the simulator's do), the
    numpy-only policy.py returns exactly spec.act's numbers, one row or a batch."""

    for name in ("structured", "structured-commanded", "structured-command-feedback"):
        _exactly_the_numpy_policy(tmp_path / name, SPECS[name])


def _exactly_the_numpy_policy(tmp_path, spec) -> None:
    import importlib.util

    tmp_path.mkdir()
    params, mean, std = _policy(spec, seed=2)
    paths = export_policy(tmp_path, spec, params, mean, std, ("npz", "py"))
    module_spec = importlib.util.spec_from_file_location("exported_policy", paths["py"])
    assert module_spec is not None and module_spec.loader is not None
    module = importlib.util.module_from_spec(module_spec)
    module_spec.loader.exec_module(module)
    policy = module.load(str(paths["npz"]))
    rng = np.random.default_rng(4)
    obs = mean + rng.normal(size=(40, 7)) * std * 3
    phi = rng.uniform(0, 2 * np.pi, 40)
    obs[:, 5], obs[:, 2] = np.sin(phi), np.cos(phi)
    ref = spec.act(np.broadcast_to(params, (40, spec.n_params)), obs, mean, std)
    assert np.array_equal(policy(obs), ref)
    assert all(np.array_equal(policy(obs[i]), ref[i]) for i in range(40))


def test_linear_and_mlp_files_keep_their_keys(tmp_path) -> None:
    """Files written before the structured kind existed have these keys and still read."""
    old = {"format_version", "kind", "obs_mean", "obs_std", "clip_obs", "n_layers",
           "output_tanh", "action_scale", "action_offset", "action_low", "action_high"}
    for name, extra in (("linear", {"layer0_weight"}),
                        ("mlp", {f"layer{k}_{w}" for k in range(3) for w in ("weight", "bias")})):
        spec = SPECS[name]
        params, mean, std = _policy(spec)
        path = write_policy_npz(tmp_path / f"{name}.npz", spec, params, mean, std)
        with np.load(path) as f:
            assert set(f.files) == old | extra
        assert np.array_equal(read_policy_npz(path).params, params)
