"""Linear and MLP policies: flat layout, batched forward = per-row forward, the action map,
initialisation and bounds, the registry; the conformance every kind in POLICIES passes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from evomotion.core.policies import POLICIES, LinearSpec, MLPSpec, StructuredSpec, make_policy
from evomotion.core.registry import UnknownNameError


def _stats(rng, o):
    return rng.normal(size=o), rng.uniform(0.3, 3.0, size=o)


def _reference(spec, p, obs, mean, std):
    """A plain per-policy forward pass written from the equations (tanh between layers)."""
    x = (obs - mean) / std
    if math.isfinite(spec.clip_obs):
        x = np.clip(x, -spec.clip_obs, spec.clip_obs)
    layers = spec.unflatten(p)
    for k, (W, b) in enumerate(layers):
        x = W @ x + (0.0 if b is None else b)
        if k < len(layers) - 1 or isinstance(spec, MLPSpec):
            x = np.tanh(x)
    return np.clip(spec.offset + spec.scale * x, spec.low, spec.high)


@pytest.mark.parametrize("spec", [
    LinearSpec(5, 3),
    LinearSpec(5, 3, bias=True, scale=0.5, offset=[0.1, 0.2, 0.3], low=-1, high=1,
               clip_obs=2.0),
    MLPSpec(5, 3, hidden=(7,)),
    MLPSpec(5, 3, hidden=(8, 4), scale=[1, 2, 3], offset=-0.5, low=[-1, -2, -3], high=0.5,
            clip_obs=5.0),
])
def test_batched_forward_equals_each_row_and_the_equations(spec) -> None:
    rng = np.random.default_rng(3)
    n = 11
    params = rng.normal(size=(n, spec.n_params))
    obs = rng.normal(size=(n, spec.obs_dim)) * 4
    mean, std = _stats(rng, spec.obs_dim)
    out = spec.act(params, obs, mean, std)
    assert out.shape == (n, spec.act_dim)
    for i in range(n):
        ref = _reference(spec, params[i], obs[i], mean, std)
        np.testing.assert_allclose(out[i], ref, rtol=0, atol=1e-12)
        np.testing.assert_allclose(spec.act_one(params[i], obs[i], mean, std), ref, atol=1e-12)
    assert (out >= spec.low).all() and (out <= spec.high).all()


def test_layout_sizes_and_flatten_round_trip() -> None:
    lin, mlp = LinearSpec(4, 2), MLPSpec(4, 2, hidden=(3, 5))
    assert lin.n_params == 8 and LinearSpec(4, 2, bias=True).n_params == 10
    assert mlp.n_params == 4 * 3 + 3 + 3 * 5 + 5 + 5 * 2 + 2
    p = np.arange(float(mlp.n_params))
    layers = mlp.unflatten(p)
    assert [W.shape for W, _ in layers] == [(3, 4), (5, 3), (2, 5)]
    assert layers[0][0][1, 0] == 4.0 and layers[0][1] is not None and layers[0][1][0] == 12.0
    assert np.array_equal(mlp.flatten(layers), p)
    assert lin.unflatten(np.zeros(8))[0][1] is None
    batch = mlp.unflatten(np.zeros((6, mlp.n_params)))
    assert batch[1][0].shape == (6, 5, 3)


def test_linear_is_unsquashed_and_mlp_squashed_into_offset_plus_minus_scale() -> None:
    lin = LinearSpec(1, 1, bias=True, scale=2.0, offset=1.0)
    assert lin.act_one(np.array([3.0, 0.5]), np.array([1.0]), np.zeros(1), np.ones(1))[0] \
        == pytest.approx(1.0 + 2.0 * 3.5)
    mlp = MLPSpec(3, 2, hidden=(4,), scale=[0.5, 0.25], offset=[1.0, -1.0])
    out = mlp.act(np.full((20, mlp.n_params), 50.0), np.random.default_rng(0).normal(
        size=(20, 3)), np.zeros(3), np.ones(3))
    assert (np.abs(out - mlp.offset) <= mlp.scale + 1e-15).all()


def test_clip_obs_bounds_the_normalised_input() -> None:
    lin = LinearSpec(1, 1, clip_obs=5.0)
    w = np.array([[1.0]])
    assert lin.act(w, np.array([[100.0]]), np.zeros(1), np.ones(1))[0, 0] == 5.0
    assert LinearSpec(1, 1).act(w, np.array([[100.0]]), np.zeros(1), np.ones(1))[0, 0] == 100


def test_initialisation_and_bounds() -> None:
    lin, mlp = LinearSpec(6, 2), MLPSpec(6, 2, hidden=(32,))
    assert np.array_equal(lin.initial_params(np.random.default_rng(0)), np.zeros(12))
    p = mlp.initial_params(np.random.default_rng(0))
    W0, b0 = mlp.unflatten(p)[0]
    limit = math.sqrt(6 / (6 + 32))  # Glorot & Bengio 2010, eq. 16
    assert np.abs(W0).max() <= limit and np.abs(W0).max() > 0.8 * limit
    assert b0 is not None and not b0.any()
    assert np.array_equal(p, mlp.initial_params(np.random.default_rng(0)))
    low, high = mlp.genome_bounds()
    assert low.shape == (mlp.n_params,) and (low == -10).all() and (high == 10).all()
    assert (mlp.genome_bounds(100.0)[1] == 100).all()


def test_registry_and_one_line_errors() -> None:
    assert set(POLICIES) == {"linear", "mlp", "structured"}
    assert isinstance(make_policy("mlp", 3, 2, hidden=[4]), MLPSpec)
    assert isinstance(make_policy("structured", 4, 2, phase_columns=(2, 3), harmonics=1),
                      StructuredSpec)
    with pytest.raises(UnknownNameError,
                       match="unknown policy 'rnn'; available: linear, mlp, structured"):
        make_policy("rnn", 3, 2)
    with pytest.raises(ValueError, match="unknown option 'hidden' for the linear policy"):
        make_policy("linear", 3, 2, hidden=[4])
    for kw in ({"obs_dim": 0}, {"scale": [1, 2, 3]}, {"low": 1, "high": 0},
               {"clip_obs": 0.0}, {"offset": math.nan}):
        args = {"obs_dim": 3, "act_dim": 2, **kw}
        with pytest.raises(ValueError) as e:
            LinearSpec(**args)
        assert "\n" not in str(e.value)
    with pytest.raises(ValueError, match="hidden"):
        MLPSpec(3, 2, hidden=())
    with pytest.raises(ValueError, match="params"):
        LinearSpec(3, 2).act(np.zeros((2, 5)), np.zeros((2, 3)), np.zeros(3), np.ones(3))
    with pytest.raises(ValueError, match="obs"):
        LinearSpec(3, 2).act(np.zeros((2, 6)), np.zeros((2, 4)), np.zeros(3), np.ones(3))


#: one example of every registered kind, with a non-trivial action map (no exemptions)
CONFORMANCE = {
    "linear": LinearSpec(6, 3, bias=True, scale=0.5, offset=[0.1, 0.2, 0.3], low=-1, high=1,
                         clip_obs=2.0),
    "mlp": MLPSpec(6, 3, hidden=(5,), scale=[1, 2, 3], offset=-0.5, low=-2, high=0.5),
    "structured": StructuredSpec(6, 3, phase_columns=(4, 1), harmonics=2, scale=[1, 2, 3],
                                 offset=[0.1, 0.0, -0.1], low=-2, high=2, clip_obs=3.0),
}


def test_every_kind_has_a_conformance_example() -> None:
    assert set(CONFORMANCE) == set(POLICIES)
    assert all(type(CONFORMANCE[k]) is POLICIES[k] and POLICIES[k].kind == k for k in POLICIES)


@pytest.mark.parametrize("kind", sorted(POLICIES))
def test_conformance(kind) -> None:
    """Whatever the kind: batched rows = one at a time, per-row normalisers = the shared one
    row by row, zero parameters = the offset (clipped), flatten inverts unflatten, the start
    and bounds have P entries, outputs within [low, high]."""
    spec = CONFORMANCE[kind]
    rng = np.random.default_rng(8)
    n, o = 9, spec.obs_dim
    params = rng.normal(size=(n, spec.n_params))
    obs = rng.normal(size=(n, o)) * 3
    means, stds = rng.normal(size=(n, o)), rng.uniform(0.3, 3.0, size=(n, o))
    out = spec.act(params, obs, means, stds)
    assert out.shape == (n, spec.act_dim)
    for i in range(n):
        one = spec.act_one(params[i], obs[i], means[i], stds[i])
        np.testing.assert_array_equal(out[i], one)
        np.testing.assert_array_equal(
            spec.act(params, obs, means[i], stds[i])[i], one)
    assert (out >= spec.low).all() and (out <= spec.high).all()
    zero = spec.act(np.zeros((n, spec.n_params)), obs, means, stds)
    np.testing.assert_array_equal(zero, np.broadcast_to(
        np.clip(spec.offset, spec.low, spec.high), zero.shape))
    assert np.array_equal(spec.flatten(spec.unflatten(params[0])), params[0])
    assert spec.initial_params(np.random.default_rng(0)).shape == (spec.n_params,)
    assert spec.genome_bounds()[0].shape == (spec.n_params,)
    with pytest.raises(ValueError, match="mean/std"):
        spec.act(params, obs, means[:2], stds[:2])
