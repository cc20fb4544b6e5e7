"""Fuzzing read_policy_npz: valid policy files corrupted at the array level (keys dropped or
added, shapes and dtypes changed, NaN / inf / huge numbers inserted, versions and kinds
changed) and at the byte level (bit flips, deletions, truncation). The only exception that may
escape is FileFormatError, as one line naming the file; whatever is accepted is a usable policy
(finite parameters and statistics, a forward pass that runs)."""

from __future__ import annotations

import io
import warnings
from collections import Counter

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from evomotion.core.policies import LinearSpec, MLPSpec, StructuredSpec
from evomotion.core.policies.export import policy_arrays, read_policy_npz
from evomotion.errors import FileFormatError

FUZZ = dict(deadline=None, database=None, derandomize=True,
            suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
_RNG = np.random.default_rng(0)
SEEDS = [policy_arrays(s, _RNG.normal(size=s.n_params), _RNG.normal(size=s.obs_dim),
                       _RNG.uniform(0.5, 2, size=s.obs_dim))
         for s in (LinearSpec(4, 2, clip_obs=5.0, low=-1, high=1), LinearSpec(3, 2, bias=True),
                   MLPSpec(4, 2, hidden=(3,), scale=[1, 2]), MLPSpec(3, 1, hidden=(2, 2)),
                   StructuredSpec(5, 2, phase_columns=(3, 4), harmonics=2, low=-1, high=1,
                                  clip_obs=4.0),
                   StructuredSpec(2, 1, phase_columns=(1, 0), harmonics=1))]
VALUES = [np.nan, np.inf, -np.inf, 1e308, -1e308, 0.0, -1.0, 2.0]


@st.composite
def mutated_arrays(draw) -> dict[str, np.ndarray]:
    arrays = {k: v.copy() for k, v in draw(st.sampled_from(SEEDS)).items()}
    for _ in range(draw(st.integers(1, 3))):
        key = draw(st.sampled_from(sorted(arrays)))
        a = arrays[key]
        op = draw(st.sampled_from(["drop", "add", "value", "shape", "dtype", "scalar",
                                   "text", "rename"]))
        if op == "drop":
            del arrays[key]
        elif op == "add":
            arrays[draw(st.sampled_from(["layer9_weight", "layer1_bias", "junk", "n_layers",
                                         "tape_coef", "harmonics", "phase_columns"]))] = \
                np.zeros(draw(st.integers(0, 3)))
        elif op == "value" and a.size and a.dtype.kind in "fiub":
            flat = a.astype(np.float64).reshape(-1)
            flat[draw(st.integers(0, flat.size - 1))] = draw(st.sampled_from(VALUES))
            arrays[key] = flat.reshape(a.shape)
        elif op == "shape":
            shape = draw(st.sampled_from([(0,), (1,), (2, 2), (5,), (3, 4), (2, 0), (2, 3)]))
            arrays[key] = np.resize(a, shape)
        elif op == "dtype":
            dtype = draw(st.sampled_from([np.float32, np.int8, np.bool_, np.complex64, "U3"]))
            try:
                with np.errstate(all="ignore"), warnings.catch_warnings():
                    warnings.simplefilter("ignore")  # complex -> real
                    arrays[key] = a.astype(dtype)
            except ValueError:  # text to numbers
                arrays[key] = np.zeros(a.shape, dtype)
        elif op == "scalar":
            arrays[key] = np.array(draw(st.sampled_from([0, 1, 2, 65, -1, 1.5])))
        elif op == "text":
            arrays[key] = np.array(draw(st.sampled_from(["mlp", "linear", "structured", "",
                                                         "x" * 70])))
        else:
            arrays["layer0_wieght"] = arrays.pop(key)
    return arrays


def _save(arrays: dict[str, np.ndarray]) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **arrays)  # type: ignore[arg-type]
    return buf.getvalue()


@st.composite
def mutated_bytes(draw) -> bytes:
    data = bytearray(_save(draw(st.sampled_from(SEEDS))))
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.integers(0, len(data) - 1))
        op = draw(st.sampled_from(["flip", "delete", "truncate"]))
        if op == "flip":
            data[i] ^= 1 << draw(st.integers(0, 7))
        elif op == "delete":
            del data[i:i + draw(st.integers(1, 32))]
        else:
            del data[i:]
        if not data:
            break
    return bytes(data)


OUTCOMES: Counter = Counter()


def _accepts_or_one_line(tmp_path, data: bytes) -> str:
    OUTCOMES["inputs"] += 1
    path = tmp_path / "policy.npz"
    path.write_bytes(data)
    try:
        got = read_policy_npz(path)
    except FileFormatError as e:
        assert "\n" not in str(e) and str(path) in str(e)
        OUTCOMES["error"] += 1
        return "error"
    spec = got.spec
    assert got.params.shape == (spec.n_params,) and np.isfinite(got.params).all()
    assert np.isfinite(got.obs_mean).all() and (got.obs_std > 0).all()
    out = spec.act_one(got.params, np.ones(spec.obs_dim), got.obs_mean, got.obs_std)
    assert out.shape == (spec.act_dim,)
    return "ok"


@settings(max_examples=400, **FUZZ)
@given(mutated_arrays())
def test_corrupted_arrays_are_read_or_one_line(tmp_path, arrays) -> None:
    _accepts_or_one_line(tmp_path, _save(arrays))


@settings(max_examples=200, **FUZZ)
@given(mutated_bytes())
def test_corrupted_bytes_are_read_or_one_line(tmp_path, data) -> None:
    _accepts_or_one_line(tmp_path, data)


def test_the_seeds_are_accepted(tmp_path) -> None:
    assert all(_accepts_or_one_line(tmp_path, _save(a)) == "ok" for a in SEEDS)


def teardown_module() -> None:
    print("\npolicy.npz fuzz:", dict(OUTCOMES))
