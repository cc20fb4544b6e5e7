"""The structured policy: the batched forward against the formula written with sin(k phi) and
cos(k phi) directly, zero parameters = the nominal pose, the parameter layout, fitting a tape
to a gait's trajectory, one-line errors for bad options."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.core.policies import StructuredSpec, fit_tape, make_policy
from evomotion.core.policies.standalone import _row_dot as policy_py_row_dot
from evomotion.core.policies.structured import _row_dot, phase_features


def _explicit(spec: StructuredSpec, p: np.ndarray, obs: np.ndarray, mean, std) -> np.ndarray:
    """One policy on one observation, from the module doc's equations (loops, np.sin)."""
    a, H, o = spec.act_dim, spec.harmonics, spec.obs_dim
    i, j = spec.phase_columns
    phi = np.arctan2(obs[i], obs[j])
    C = p[:a * (1 + 2 * H)].reshape(a, 1 + 2 * H)
    K = p[a * (1 + 2 * H):].reshape(a, o - 2)
    x = np.clip((obs - mean) / std, -spec.clip_obs, spec.clip_obs)
    x = np.array([x[m] for m in range(o) if m not in (i, j)])
    y = np.zeros(a)
    for r in range(a):
        y[r] = C[r, 0] + sum(C[r, 2 * k - 1] * np.sin(k * phi) + C[r, 2 * k] * np.cos(k * phi)
                             for k in range(1, H + 1))
        y[r] += sum(K[r, m] * x[m] for m in range(o - 2))
    return np.clip(spec.offset + spec.scale * y, spec.low, spec.high)


@settings(max_examples=60, deadline=None, derandomize=True, database=None)
@given(n=st.integers(1, 6), o=st.integers(2, 7), a=st.integers(1, 4), H=st.integers(0, 4),
       seed=st.integers(0, 2**31), clip=st.sampled_from([np.inf, 1.5]))
def test_batched_act_is_the_formula_row_by_row(n, o, a, H, seed, clip) -> None:
    rng = np.random.default_rng(seed)
    cols = tuple(int(c) for c in rng.choice(o, size=2, replace=False))
    spec = StructuredSpec(o, a, phase_columns=cols, harmonics=H, clip_obs=clip,
                          scale=rng.uniform(0.5, 2, a), offset=rng.normal(size=a),
                          low=-3.0, high=3.0)
    assert spec.n_params == a * (1 + 2 * H) + a * (o - 2)
    params = rng.normal(size=(n, spec.n_params))
    obs = rng.normal(size=(n, o)) * 2
    phi = rng.uniform(-np.pi, np.pi, n)
    obs[:, cols[0]], obs[:, cols[1]] = np.sin(phi), np.cos(phi)  # the raw clock columns
    mean, std = rng.normal(size=o), rng.uniform(0.3, 3, o)
    out = spec.act(params, obs, mean, std)
    for r in range(n):
        np.testing.assert_allclose(out[r], _explicit(spec, params[r], obs[r], mean, std),
                                   rtol=0, atol=1e-9)


@settings(max_examples=60, deadline=None, derandomize=True, database=None)
@given(n=st.integers(1, 5), a=st.integers(1, 6), m=st.integers(1, 40),
       shared=st.booleans(), seed=st.integers(0, 2**31), specials=st.booleans())
def test_row_dot_sums_in_column_order_bit_for_bit(n, a, m, shared, seed, specials) -> None:
    """The batched sum (products, then a running sum) gives the bits of ``policy.py``'s column
    loop (the exported numpy policy, :mod:`evomotion.core.policies.standalone`): with one
    matrix for every row or one per row, over magnitudes 1e-8..1e8 where the order of
    additions shows, with NaN and infinities where they fall."""
    rng = np.random.default_rng(seed)
    shape = (a, m) if shared else (n, a, m)
    W = rng.normal(size=shape) * 10.0 ** rng.uniform(-8, 8, shape)
    v = rng.normal(size=(n, m)) * 10.0 ** rng.uniform(-8, 8, (n, m))
    if specials:
        W.flat[rng.integers(W.size)] = np.nan
        v.flat[rng.integers(v.size)] = rng.choice([np.inf, -np.inf])
    got, want = _row_dot(W, v), policy_py_row_dot(W, v)
    assert got.shape == want.shape == (n, a)
    assert np.array_equal(got.view(np.uint64), want.view(np.uint64))


def test_the_phase_columns_are_read_raw_and_the_rest_normalised() -> None:
    spec = StructuredSpec(4, 1, phase_columns=(0, 3), harmonics=1)
    p = spec.params_from_tape(np.array([[0.0, 1.0, 0.0]]))  # y = sin(phi)
    obs = np.array([[0.6, 5.0, -5.0, 0.8]])
    # a normaliser that would change the phase columns changes nothing
    assert spec.act(p[None], obs, np.full(4, 3.0), np.full(4, 7.0))[0, 0] == 0.6
    gain = spec.flatten([(np.zeros((1, 3)), None), (np.array([[0.0, 2.0]]), None)])
    assert spec.act(gain[None], obs, np.full(4, 1.0), np.full(4, 2.0))[0, 0] == -6.0


def test_zero_parameters_are_the_nominal_pose() -> None:
    spec = make_policy("structured", 8, 3, phase_columns=(6, 7), harmonics=3,
                       offset=[0.2, -0.4, 1.5], low=-1.0, high=1.0, scale=0.3)
    obs = np.random.default_rng(1).normal(size=(5, 8))
    out = spec.act(np.zeros((5, spec.n_params)), obs, np.zeros(8), np.ones(8))
    assert np.array_equal(out, np.tile([0.2, -0.4, 1.0], (5, 1)))
    assert np.array_equal(spec.initial_params(np.random.default_rng(0)),
                          np.zeros(spec.n_params))


def test_layout_tape_first_then_gains_row_major() -> None:
    spec = StructuredSpec(5, 2, phase_columns=(1, 3), harmonics=1)
    p = np.arange(float(spec.n_params))
    (C, b0), (K, b1) = spec.unflatten(p)
    assert b0 is None and b1 is None
    assert C.tolist() == [[0, 1, 2], [3, 4, 5]] and K.tolist() == [[6, 7, 8], [9, 10, 11]]
    assert spec.feedback_columns.tolist() == [0, 2, 4]


def test_the_recurrence_is_sin_and_cos_of_multiples() -> None:
    phi = np.linspace(-7, 7, 101)
    f = phase_features(np.sin(phi), np.cos(phi), 6)
    want = [np.ones_like(phi)]
    for k in range(1, 7):
        want += [np.sin(k * phi), np.cos(k * phi)]
    np.testing.assert_allclose(f, np.stack(want, -1), rtol=0, atol=1e-12)


def test_fit_tape_recovers_a_signal_and_seeds_the_policy() -> None:
    rng = np.random.default_rng(3)
    period = 0.8
    true = rng.normal(size=(3, 5))  # 3 joints, H = 2
    t = np.sort(rng.uniform(0, 2.4, 60))
    phi = 2 * np.pi * t / period
    F = np.stack([np.ones_like(phi), np.sin(phi), np.cos(phi), np.sin(2 * phi),
                  np.cos(2 * phi)], -1)
    coeffs = fit_tape(t, F @ true.T, period, 2)
    np.testing.assert_allclose(coeffs, true, atol=1e-10)
    noisy = fit_tape(t, F @ true.T + rng.normal(scale=0.01, size=(60, 3)), period, 2)
    assert np.abs(noisy - true).max() < 0.02
    # the seeded policy plays the trajectory back, whatever its other sensors read
    spec = StructuredSpec(6, 3, phase_columns=(4, 5), harmonics=2, offset=[0.1, 0.2, 0.3],
                          scale=0.5)
    p = spec.params_from_tape(coeffs)
    obs = rng.normal(size=(60, 6))
    obs[:, 4], obs[:, 5] = np.sin(phi), np.cos(phi)
    out = spec.act(np.broadcast_to(p, (60, spec.n_params)), obs, np.zeros(6), np.ones(6))
    np.testing.assert_allclose(out, spec.offset + 0.5 * (F @ true.T), atol=1e-9)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({}, "needs phase_columns"),
    ({"phase_columns": (1, 1)}, "two different columns in 0..4"),
    ({"phase_columns": (0, 5)}, "two different columns in 0..4"),
    ({"phase_columns": (-1, 2)}, "two different columns in 0..4"),
    ({"phase_columns": (1, 2, 3)}, "must be two column numbers"),
    ({"phase_columns": 3}, "must be two column numbers"),
    ({"phase_columns": (1.0, 2)}, "must be two column numbers"),
    ({"phase_columns": (True, 2)}, "must be two column numbers"),
    ({"phase_columns": (0, 1), "harmonics": -1}, "harmonics must be a whole number"),
    ({"phase_columns": (0, 1), "harmonics": 2.0}, "harmonics must be a whole number"),
    ({"phase_columns": (0, 1), "hidden": (3,)}, "unknown option 'hidden'"),
])
def test_bad_options_are_one_line(kwargs, message) -> None:
    with pytest.raises(ValueError) as e:
        make_policy("structured", 5, 2, **kwargs)
    assert message in str(e.value) and "\n" not in str(e.value)


@pytest.mark.parametrize(("args", "message"), [
    ((np.zeros(3), np.zeros((3, 2)), 0.0, 1), "period_s"),
    ((np.zeros(3), np.zeros((4, 2)), 1.0, 1), "expected, got shapes"),
    ((np.zeros(3), np.zeros((3, 2)), 1.0, 1), "do not determine 3 tape coefficients"),
    ((np.array([0.0, 1.0, np.nan]), np.zeros((3, 2)), 1.0, 1), "finite"),
    ((np.linspace(0, 1, 9), np.zeros((9, 2)), 1.0, 1.5), "harmonics"),
])
def test_fit_tape_errors_are_one_line(args, message) -> None:
    with pytest.raises(ValueError) as e:
        fit_tape(*args)
    assert message in str(e.value) and "\n" not in str(e.value)
    spec = StructuredSpec(3, 2, phase_columns=(0, 1), harmonics=1)
    with pytest.raises(ValueError, match=r"shape \(2, 3\)"):
        spec.params_from_tape(np.zeros((2, 5)))


def test_a_command_modulates_every_harmonic_affinely() -> None:
    """tape(phi, c) = C_0 f(phi) + sum_i c_i C_i f(phi): the columns of c_i f after those of f,
    the command read raw; zero command = the plain tape."""
    rng = np.random.default_rng(3)
    spec = StructuredSpec(6, 2, phase_columns=(0, 1), harmonics=1, command_columns=(4, 2))
    assert spec.n_features == 3 * 3 and spec.n_params == 2 * 9 + 2 * 4
    C = rng.normal(size=(2, 9))
    p = spec.params_from_tape(C)
    phi, c = 0.7, np.array([0.3, -1.2])
    obs = np.array([[np.sin(phi), np.cos(phi), c[1], 9.0, c[0], 5.0]])
    f = np.array([1.0, np.sin(phi), np.cos(phi)])
    want = C[:, :3] @ f + c[0] * (C[:, 3:6] @ f) + c[1] * (C[:, 6:] @ f)
    got = spec.act(p[None], obs, np.full(6, 2.0), np.full(6, 3.0))[0]
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    obs[0, [4, 2]] = 0.0
    np.testing.assert_allclose(spec.act(p[None], obs, np.zeros(6), np.ones(6))[0],
                               C[:, :3] @ f, rtol=0, atol=1e-12)


def test_fit_tape_with_commands_recovers_a_commanded_gait() -> None:
    rng = np.random.default_rng(5)
    true = rng.normal(size=(3, 5 * 3))  # H = 2, m = 2
    t = np.linspace(0, 4, 401)
    cmd = rng.uniform(-1, 1, size=(t.size, 2))
    phi = 2 * np.pi * t / 0.5
    f = phase_features(np.sin(phi), np.cos(phi), 2)
    g = np.concatenate([f, cmd[:, :1] * f, cmd[:, 1:] * f], axis=1)
    coeffs = fit_tape(t, g @ true.T, 0.5, 2, commands=cmd)
    np.testing.assert_allclose(coeffs, true, atol=1e-9)


@pytest.mark.parametrize("cols", [(0,), (1, 3, 1), (9,), (True,), ("a",)])
def test_bad_command_columns_are_one_line(cols) -> None:
    with pytest.raises(ValueError, match="command_columns") as e:
        StructuredSpec(4, 1, phase_columns=(0, 1), command_columns=cols)
    assert "\n" not in str(e.value)


def test_command_feedback_shifts_the_command_the_tape_reads() -> None:
    """With command feedback the tape reads c + G x (x: the normalised observation without the
    phase columns, clipped); G = 0 is the plain command-modulated tape, bit for bit."""
    rng = np.random.default_rng(8)
    plain = StructuredSpec(6, 2, phase_columns=(0, 1), harmonics=2, command_columns=(4, 2),
                           clip_obs=3.0)
    fed = StructuredSpec(6, 2, phase_columns=(0, 1), harmonics=2, command_columns=(4, 2),
                         clip_obs=3.0, command_feedback=True)
    assert fed.n_params == plain.n_params + 2 * 4
    p = rng.normal(size=plain.n_params)
    G = rng.normal(size=(2, 4))
    mean, std = rng.normal(size=6), rng.uniform(0.5, 2.0, 6)
    obs = rng.normal(size=(5, 6)) * 2
    phi = rng.uniform(0, 2 * np.pi, 5)
    obs[:, 0], obs[:, 1] = np.sin(phi), np.cos(phi)
    zero = np.concatenate([p, np.zeros(8)])
    rows = np.ones((5, 1))
    assert np.array_equal(fed.act(zero * rows, obs, mean, std), plain.act(p * rows, obs, mean, std))
    x = np.clip((obs - mean) / std, -3, 3)[:, [2, 3, 4, 5]]
    shifted = obs.copy()
    shifted[:, [4, 2]] += x @ G.T  # what the tape reads; K x still sees the raw command
    got = fed.act(np.concatenate([p, G.ravel()]) * rows, obs, mean, std)
    (C, _), (K, _) = plain.unflatten(p)
    want = np.clip(plain.offset + plain.scale * (plain.features(shifted) @ C.T + x @ K.T),
                   plain.low, plain.high)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="command_feedback"):
        StructuredSpec(6, 2, phase_columns=(0, 1), command_feedback=True)
