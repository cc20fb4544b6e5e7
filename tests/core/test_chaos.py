"""Tent map: range, non-periodicity for valid parameters, invalid starts."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.core.chaos import tent_interval, tent_sequence, tent_to_box, validate_tent


@settings(max_examples=40, deadline=None)
@given(mu=st.floats(1.05, 1.95), x0=st.floats(0.01, 0.99))
def test_tent_range_and_invariant_interval(mu, x0):
    if abs(x0 - mu / (1 + mu)) < 1e-6:
        return
    seq = tent_sequence(x0, mu, 400)
    assert np.all((seq >= 0) & (seq <= 1))
    a, b = tent_interval(mu)
    assert np.all((seq[200:] >= a - 1e-12) & (seq[200:] <= b + 1e-12))


@settings(max_examples=25, deadline=None)
@given(mu=st.floats(1.2, 1.95), x0=st.floats(0.05, 0.95))
def test_tent_not_periodic(mu, x0):
    if abs(x0 - mu / (1 + mu)) < 1e-3:
        return
    seq = tent_sequence(x0, mu, 600)[100:]
    for period in range(1, 60):
        assert np.max(np.abs(seq[period:] - seq[:-period])) > 1e-6, period
    assert np.unique(np.round(seq, 12)).size > 0.95 * seq.size


def test_paper_figure_case_covers_the_invariant_interval():
    seq = tent_sequence(0.8, 1.5, 500)[50:]  # paper 002, Fig. 1: x0 = 0.8, mu = 1.5
    a, b = tent_interval(1.5)
    hist, _ = np.histogram(seq, bins=10, range=(a, b))
    assert np.all(hist > 0)


def test_fixed_point_and_bad_parameters_rejected():
    with pytest.raises(ValueError):
        validate_tent(1.5, 1.5 / 2.5)
    for mu, x0 in ((1.0, 0.3), (2.0, 0.3), (1.5, 0.0), (1.5, 1.0)):
        with pytest.raises(ValueError):
            validate_tent(mu, x0)


def test_tent_to_box_maps_interval_to_bounds():
    lo, hi = np.array([-2.0, 0.0]), np.array([2.0, 10.0])
    a, b = tent_interval(1.5)
    c = tent_to_box(np.array([[a, b], [b, a], [(a + b) / 2] * 2]), 1.5, lo, hi)
    assert np.allclose(c, [[-2, 10], [2, 0], [0, 5]])
