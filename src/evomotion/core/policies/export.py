"""Policies that leave the project: ``policy.npz``, a numpy-only ``policy.py``, ``policy.onnx``.

Each takes the raw observation and returns the action (normalisation inside), so a plain
Gymnasium or robot loop runs it with nothing of evomotion installed.

``policy.npz`` (format version 1) holds, as named arrays: ``format_version`` (int), ``kind``
("linear", "mlp" or "structured"), ``obs_mean[o]``, ``obs_std[o]``, ``clip_obs`` (+inf: none),
``output_tanh`` (0/1), ``action_scale[a]``, ``action_offset[a]``, ``action_low[a]``,
``action_high[a]`` (±inf: no bound); then linear and MLP policies ``n_layers``,
``layer{k}_weight[out, in]`` and ``layer{k}_bias[out]`` (absent for a layer without one), and
structured ones (:mod:`.structured`) ``harmonics`` (H), ``phase_columns[2]`` (the raw sin and
cos columns), ``command_columns[m]`` (the raw command columns that modulate the tape; may be
absent: none), ``tape_coef[a, (1 + 2H)(1 + m)]``, ``feedback_gain[a, o − 2]`` and, with
command feedback, ``command_gain[m, o − 2]`` (absent: none). ``policy.py`` is
:mod:`.standalone` as text; ``policy.onnx`` is built by :mod:`.onnx_graph`.
:func:`read_policy_npz` reads a file back with one-line errors for whatever is wrong with it.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from evomotion.core.policies import POLICIES
from evomotion.core.policies.linear import LinearSpec
from evomotion.core.policies.mlp import MLPSpec
from evomotion.core.policies.spec import PolicySpec
from evomotion.core.policies.structured import MAX_HARMONICS, StructuredSpec
from evomotion.errors import FileFormatError
from evomotion.npzio import read_npz
from evomotion.outfile import atomic_write_bytes, atomic_write_text
from evomotion.textio import decode_utf8, read_file_bytes

FORMAT_VERSION = 1
MAX_POLICY_BYTES = 64 * 1024 * 1024
MAX_LAYERS = 64
_KINDS: dict[str, type[PolicySpec]] = POLICIES
_FIXED = ("format_version", "kind", "obs_mean", "obs_std", "clip_obs", "output_tanh",
          "action_scale", "action_offset", "action_low", "action_high")
_STRUCTURED = ("harmonics", "phase_columns", "tape_coef", "feedback_gain")
#: absent: no command, no command feedback (files written before they existed)
_OPTIONAL = ("command_columns", "command_gain")


@dataclass(frozen=True, eq=False)
class ExportedPolicy:
    """A policy read back: its spec, flat ``params[P]`` and normaliser ``obs_mean``/``obs_std``."""

    spec: PolicySpec
    params: np.ndarray
    obs_mean: np.ndarray
    obs_std: np.ndarray


def policy_arrays(spec: PolicySpec, params: np.ndarray, obs_mean: np.ndarray,
                  obs_std: np.ndarray) -> dict[str, np.ndarray]:
    """The named arrays of ``policy.npz`` (see the module)."""
    mean = np.asarray(obs_mean, dtype=np.float64)
    std = np.asarray(obs_std, dtype=np.float64)
    if mean.shape != (spec.obs_dim,) or std.shape != (spec.obs_dim,):
        raise ValueError(f"obs_mean/obs_std have shapes {mean.shape}/{std.shape}, expected "
                         f"({spec.obs_dim},)")
    if not (np.isfinite(mean).all() and np.isfinite(std).all() and (std > 0).all()):
        raise ValueError("obs_mean must be finite and obs_std finite and > 0")
    p = np.asarray(params, dtype=np.float64)
    if p.shape != (spec.n_params,) or not np.isfinite(p).all():
        raise ValueError(f"params must be {spec.n_params} finite numbers, got shape {p.shape}")
    arrays = {"format_version": np.array(FORMAT_VERSION, dtype=np.int64),
              "kind": np.array(spec.kind), "obs_mean": mean, "obs_std": std,
              "clip_obs": np.array(spec.clip_obs), "output_tanh": np.array(spec.squash_output),
              "action_scale": np.asarray(spec.scale), "action_offset": np.asarray(spec.offset),
              "action_low": np.asarray(spec.low), "action_high": np.asarray(spec.high)}
    layers = spec.unflatten(p)
    if isinstance(spec, StructuredSpec):
        arrays.update(harmonics=np.array(spec.harmonics, dtype=np.int64),
                      phase_columns=np.array(spec.phase_columns, dtype=np.int64),
                      command_columns=np.array(spec.command_columns, dtype=np.int64),
                      tape_coef=np.ascontiguousarray(layers[0][0]),
                      feedback_gain=np.ascontiguousarray(layers[1][0]))
        if spec.command_feedback:
            arrays["command_gain"] = np.ascontiguousarray(layers[2][0])
        return arrays
    arrays["n_layers"] = np.array(len(layers), dtype=np.int64)
    for k, (W, b) in enumerate(layers):
        arrays[f"layer{k}_weight"] = np.ascontiguousarray(W)
        if b is not None:
            arrays[f"layer{k}_bias"] = np.ascontiguousarray(b)
    return arrays


def write_policy_npz(path: str | Path, spec: PolicySpec, params: np.ndarray,
                     obs_mean: np.ndarray, obs_std: np.ndarray) -> Path:
    """``policy.npz`` at ``path``, written atomically."""
    buf = io.BytesIO()
    np.savez(buf, **policy_arrays(spec, params, obs_mean, obs_std))  # type: ignore[arg-type]
    return atomic_write_bytes(path, buf.getvalue(), "policy file")


def standalone_source() -> str:
    """The text of the numpy-only ``policy.py`` (:mod:`.standalone`)."""
    src = Path(__file__).with_name("standalone.py")
    return decode_utf8(read_file_bytes(src, "policy.py template"), src)


def write_policy_py(path: str | Path) -> Path:
    """The numpy-only ``policy.py`` that loads and runs a ``policy.npz``."""
    return atomic_write_text(path, standalone_source(), "policy script")


def write_policy_onnx(path: str | Path, spec: PolicySpec, params: np.ndarray,
                      obs_mean: np.ndarray, obs_std: np.ndarray) -> Path:
    """``policy.onnx`` (needs the ``onnx`` extra): see :mod:`.onnx_graph`."""
    from evomotion.core.policies.onnx_graph import policy_model

    policy_arrays(spec, params, obs_mean, obs_std)  # the same checks as policy.npz
    model = policy_model(spec, params, obs_mean, obs_std)
    return atomic_write_bytes(path, model.SerializeToString(), "ONNX policy")


def export_policy(folder: str | Path, spec: PolicySpec, params: np.ndarray,
                  obs_mean: np.ndarray, obs_std: np.ndarray,
                  formats: tuple[str, ...] = ("npz", "py", "onnx")) -> dict[str, Path]:
    """Write ``policy.npz``/``policy.py``/``policy.onnx`` (those in ``formats``) to ``folder``."""
    writers = {"npz": lambda p: write_policy_npz(p, spec, params, obs_mean, obs_std),
               "py": write_policy_py,
               "onnx": lambda p: write_policy_onnx(p, spec, params, obs_mean, obs_std)}
    bad = [f for f in formats if f not in writers]
    if bad:
        raise ValueError(f"unknown policy format {bad[0]!r}; available: npz, onnx, py")
    policy_arrays(spec, params, obs_mean, obs_std)  # check everything before writing anything
    return {f: writers[f](Path(folder) / f"policy.{f}") for f in formats}


def read_policy_npz(path: str | Path) -> ExportedPolicy:
    """The policy in ``policy.npz`` at ``path``; anything wrong is one FileFormatError line."""
    arrays = read_npz(path, "policy file", MAX_POLICY_BYTES)

    def bad(key: str, msg: str) -> FileFormatError:
        return FileFormatError(path, None, f"expected a valid policy file: {key!r} {msg}")

    for key in _FIXED:
        if key not in arrays:
            raise bad(key, "is missing")
    version = _integer(arrays, "format_version", bad)
    if version != FORMAT_VERSION:
        raise bad("format_version", f"is {version}, this reader knows {FORMAT_VERSION}")
    kind_arr = arrays["kind"]
    if kind_arr.shape != () or kind_arr.dtype.kind != "U" or str(kind_arr) not in _KINDS:
        raise bad("kind", f"must be one of {', '.join(sorted(_KINDS))}")
    cls = _KINDS[str(kind_arr)]
    if cls is StructuredSpec:
        layers, known, options = _structured(arrays, bad)
    else:
        if "n_layers" not in arrays:
            raise bad("n_layers", "is missing")
        n_layers = _integer(arrays, "n_layers", bad)
        if not 1 <= n_layers <= MAX_LAYERS or (cls is LinearSpec) != (n_layers == 1):
            raise bad("n_layers", f"is {n_layers}, impossible for a {cls.kind} policy")
        layers, known = _layers(arrays, n_layers, cls, bad)
        known.add("n_layers")
        options = {"bias": layers[0][1] is not None} if cls is LinearSpec else \
            {"hidden": tuple(W.shape[0] for W, _ in layers[:-1])}
    extra = sorted(set(arrays) - set(_FIXED) - known)
    if extra:
        raise bad(extra[0][:60], "is not a key of a policy file")
    a = (layers[1] if cls is StructuredSpec else layers[-1])[0].shape[0]
    o = layers[1][0].shape[1] + 2 if cls is StructuredSpec else layers[0][0].shape[1]
    vec = {k: _floats(arrays, k, (o if k.startswith("obs") else a,), bad)
           for k in _FIXED if k.startswith(("obs_", "action_"))}
    for key in ("obs_mean", "obs_std", "action_scale", "action_offset"):
        if not np.isfinite(vec[key]).all():
            raise bad(key, "holds a non-finite number")
    if not (vec["obs_std"] > 0).all():
        raise bad("obs_std", "must be > 0")
    clip_obs = _floats(arrays, "clip_obs", (), bad)
    tanh = arrays["output_tanh"]
    if tanh.shape != () or tanh.dtype.kind not in "biu" or bool(tanh) != cls.squash_output:
        raise bad("output_tanh", f"must be {int(cls.squash_output)} for a {cls.kind} policy")
    try:
        spec = cls(obs_dim=o, act_dim=a, scale=vec["action_scale"],
                   offset=vec["action_offset"], low=vec["action_low"],
                   high=vec["action_high"], clip_obs=float(clip_obs), **options)
    except ValueError as e:
        raise FileFormatError(path, None, f"expected a valid policy file: {e}") from None
    return ExportedPolicy(spec, spec.flatten(layers), vec["obs_mean"], vec["obs_std"])


def _structured(arrays: dict[str, np.ndarray], bad
                ) -> tuple[list[tuple[np.ndarray, np.ndarray | None]], set[str], dict]:
    """The checked tape and gains of a structured policy, its keys and its options."""
    for key in _STRUCTURED:
        if key not in arrays:
            raise bad(key, "is missing")
    h = _integer(arrays, "harmonics", bad)
    if not 0 <= h <= MAX_HARMONICS:
        raise bad("harmonics", f"is {h}, expected 0..{MAX_HARMONICS}")
    cols = arrays["phase_columns"]
    if cols.shape != (2,) or cols.dtype.kind not in "iu":
        raise bad("phase_columns", f"must be two whole numbers, got {cols.dtype} of shape "
                  f"{cols.shape}")
    cmd = arrays.get("command_columns", np.zeros(0, np.int64))
    if cmd.ndim != 1 or (cmd.size and cmd.dtype.kind not in "iu"):
        raise bad("command_columns", f"must be whole numbers, got {cmd.dtype} of shape "
                  f"{cmd.shape}")
    width = (1 + 2 * h) * (1 + cmd.size)
    tape, gain = arrays["tape_coef"], arrays["feedback_gain"]
    if tape.ndim != 2 or tape.shape[0] < 1 or tape.shape[1] != width:
        raise bad("tape_coef", f"must be a matrix [a, {width}], got shape {tape.shape}")
    if gain.ndim != 2 or gain.shape[0] != tape.shape[0]:
        raise bad("feedback_gain", f"must be a matrix [{tape.shape[0]}, o - 2], got shape "
                  f"{gain.shape}")
    feedback = "command_gain" in arrays
    if feedback and (arrays["command_gain"].shape != (cmd.size, gain.shape[1]) or not cmd.size):
        raise bad("command_gain", f"must be a matrix [{cmd.size}, {gain.shape[1]}] (commands x "
                  f"o - 2), got shape {arrays['command_gain'].shape}")
    layers: list[tuple[np.ndarray, np.ndarray | None]] = []
    for key in ("tape_coef", "feedback_gain", "command_gain")[:3 if feedback else 2]:
        W = _floats(arrays, key, arrays[key].shape, bad)
        if not np.isfinite(W).all():
            raise bad(key, "holds a non-finite number")
        layers.append((W, None))
    options = {"harmonics": h, "phase_columns": tuple(int(c) for c in cols),
               "command_columns": tuple(int(c) for c in cmd), "command_feedback": feedback}
    return layers, set(_STRUCTURED) | set(_OPTIONAL), options


def _integer(arrays: dict[str, np.ndarray], key: str, bad) -> int:
    a = arrays[key]
    if a.shape != () or a.dtype.kind not in "iu":
        raise bad(key, f"must be one whole number, got {a.dtype} of shape {a.shape}")
    return int(a)


def _floats(arrays: dict[str, np.ndarray], key: str, shape: tuple[int, ...], bad) -> np.ndarray:
    a = arrays[key]
    if a.dtype.kind not in "iuf" or a.shape != shape:
        raise bad(key, f"must be numbers of shape {shape}, got {a.dtype} of shape {a.shape}")
    a = a.astype(np.float64)
    if np.isnan(a).any():
        raise bad(key, "holds NaN")
    return a


def _layers(arrays: dict[str, np.ndarray], n_layers: int, cls: type[PolicySpec], bad
            ) -> tuple[list[tuple[np.ndarray, np.ndarray | None]], set[str]]:
    """The checked ``(W, b)`` of every layer and the keys they used."""
    layers: list[tuple[np.ndarray, np.ndarray | None]] = []
    known: set[str] = set()
    for k in range(n_layers):
        wk, bk = f"layer{k}_weight", f"layer{k}_bias"
        if wk not in arrays:
            raise bad(wk, "is missing")
        W = arrays[wk]
        if W.ndim != 2 or min(W.shape) < 1:
            raise bad(wk, f"must be a matrix [out, in], got shape {W.shape}")
        if k > 0 and W.shape[1] != layers[-1][0].shape[0]:
            raise bad(wk, f"has {W.shape[1]} inputs after a layer of {layers[-1][0].shape[0]}")
        W = _floats(arrays, wk, W.shape, bad)
        b = None
        if bk in arrays:
            b = _floats(arrays, bk, (W.shape[0],), bad)
            known.add(bk)
        elif cls is MLPSpec:
            raise bad(bk, "is missing")
        if not np.isfinite(W).all() or (b is not None and not np.isfinite(b).all()):
            raise bad(wk if not np.isfinite(W).all() else bk, "holds a non-finite number")
        known.add(wk)
        layers.append((W, b))
    return layers, known


__all__ = ["FORMAT_VERSION", "ExportedPolicy", "export_policy", "policy_arrays",
           "read_policy_npz", "standalone_source", "write_policy_npz", "write_policy_onnx",
           "write_policy_py"]
