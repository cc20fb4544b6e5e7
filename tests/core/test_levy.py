"""Mantegna Lévy steps: heavy tail with index beta (quantile check), scale, determinism."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.core.levy import levy_flight, mantegna_sigma_u, mantegna_steps


def test_sigma_u_for_beta_1_5():
    assert mantegna_sigma_u(1.5) == pytest.approx(0.6966, abs=1e-4)
    with pytest.raises(ValueError):
        mantegna_sigma_u(2.5)


def test_heavy_tail_quantiles():
    s = np.abs(mantegna_steps(np.random.default_rng(0), 2_000_000, beta=1.5))
    q99, q999, q9999 = np.quantile(s, [0.99, 0.999, 0.9999])
    # power-law tail P(|s| > x) ~ x^-beta: each decade of probability multiplies the
    # quantile by 10^(1/beta) = 4.64; a Gaussian gives about 1.3
    assert 4.64 * 0.8 < q999 / q99 < 4.64 * 1.2
    assert 4.64 * 0.8 < q9999 / q999 < 4.64 * 1.2
    gauss = np.abs(np.random.default_rng(1).standard_normal(2_000_000))
    assert q9999 > 20 * np.quantile(gauss, 0.9999)


def test_flight_is_deterministic_per_seed_and_scaled_by_alpha():
    x = np.zeros((4, 3))
    a = levy_flight(x, 0.01, np.random.default_rng(5))
    b = levy_flight(x, 0.01, np.random.default_rng(5))
    c = levy_flight(x, 0.02, np.random.default_rng(5))
    assert np.array_equal(a, b) and np.allclose(c, 2 * a)
