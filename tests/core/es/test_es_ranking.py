"""Fitness shaping of :mod:`evomotion.core.es.ranking`: invariants (hypothesis) and ties."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from evomotion.core.es.ranking import centered_ranks, nes_utilities

costs = st.lists(st.one_of(st.integers(-5, 5).map(float),
                           st.floats(-1e6, 1e6, allow_nan=False),
                           st.just(np.inf)), min_size=2, max_size=60).map(np.array)


@given(costs)
def test_centered_ranks_sum_zero_bounded_and_order_reversing(c):
    u = centered_ranks(c)
    assert abs(u.sum()) < 1e-9
    assert np.all(u >= -0.5) and np.all(u <= 0.5)
    lower = c[:, None] < c[None, :]
    assert np.all(u[:, None] > u[None, :], where=lower)  # lower cost: strictly higher utility
    assert np.all(u[:, None] == u[None, :], where=c[:, None] == c[None, :])  # ties equal


@given(costs, st.randoms(use_true_random=False))
def test_centered_ranks_do_not_depend_on_row_order(c, r):
    perm = np.array(r.sample(range(len(c)), len(c)))
    np.testing.assert_allclose(centered_ranks(c)[perm], centered_ranks(c[perm]), atol=1e-12)


def test_centered_ranks_values_and_ties():
    np.testing.assert_allclose(centered_ranks(np.array([3.0, 1.0, 2.0])), [-0.5, 0.5, 0.0])
    # two equal lowest costs share the positions 0 and 1: (0.5 + 1/6) / 2
    np.testing.assert_allclose(centered_ranks(np.array([1.0, 1.0, 2.0, 3.0])),
                               [1 / 3, 1 / 3, -1 / 6, -0.5])
    np.testing.assert_array_equal(centered_ranks(np.array([np.nan, 0.0])), [-0.5, 0.5])
    assert centered_ranks(np.array([4.0])).tolist() == [0.0]


@given(costs)
def test_nes_utilities_sum_zero_and_order(c):
    u = nes_utilities(c)
    assert abs(u.sum()) < 1e-9
    lower = c[:, None] < c[None, :]
    assert np.all(u[:, None] >= u[None, :] - 1e-12, where=lower)  # weakly (the worse half)
    assert u.min() >= -1.0 / len(c) - 1e-12


def test_nes_utilities_match_the_formula():
    lam = 6
    k = np.arange(1, lam + 1)
    raw = np.maximum(0, np.log(lam / 2 + 1) - np.log(k))
    want = raw / raw.sum() - 1 / lam
    cost = np.array([5.0, 0.0, 3.0, 1.0, 4.0, 2.0])  # ranks 6, 1, 4, 2, 5, 3
    np.testing.assert_allclose(nes_utilities(cost), want[[5, 0, 3, 1, 4, 2]])
