"""Greedy, optimal and random-key matchings."""

from __future__ import annotations

import itertools

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import linear_sum_assignment

from evomotion.studies.arm_ik.objective import greedy_match, keys_match, matched, optimal_match


def test_greedy_is_suboptimal_where_optimal_is_not():
    # greedy takes the 1.0 pair first and is left with 10; the optimum is 2 + 2
    D = np.array([[[1.0, 2.0], [2.0, 10.0]]])
    assert greedy_match(D).tolist() == [[0, 1]]
    assert optimal_match(D).tolist() == [[1, 0]]
    assert matched(D, optimal_match(D)).sum() == 4.0


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 6), st.integers(0, 10_000))
def test_optimal_equals_hungarian_and_beats_greedy(F, seed):
    rng = np.random.default_rng(seed)
    D = rng.random((5, F, F)) * 10
    opt = optimal_match(D)
    gre = greedy_match(D)
    for i in range(5):
        assert sorted(opt[i]) == list(range(F)) and sorted(gre[i]) == list(range(F))
        r, c = linear_sum_assignment(D[i])
        assert np.isclose(D[i][r, c].sum(), matched(D[i:i + 1], opt[i:i + 1]).sum())
    assert np.all(matched(D, opt).sum(1) <= matched(D, gre).sum(1) + 1e-12)


def test_optimal_many_fingers_uses_hungarian():
    rng = np.random.default_rng(1)
    D = rng.random((3, 8, 8))
    opt = optimal_match(D)
    for i in range(3):
        r, c = linear_sum_assignment(D[i])
        np.testing.assert_array_equal(opt[i, r], c)


def test_keys_decode_to_permutations():
    keys = np.array([[0.9, 0.1, 0.5], [0.1, 0.2, 0.3]])
    assert keys_match(keys).tolist() == [[1, 2, 0], [0, 1, 2]]
    for p in itertools.permutations(range(3)):
        k = np.empty(3)
        k[list(p)] = [0.1, 0.5, 0.9]
        assert keys_match(k[None])[0].tolist() == list(p)


def test_greedy_handles_infinite_distances():
    D = np.full((2, 3, 3), np.inf)
    D[1, 0, 2] = 1.0
    a = greedy_match(D)
    assert all(sorted(r) == [0, 1, 2] for r in a.tolist()) and a[1, 0] == 2
    assert sorted(optimal_match(D)[0].tolist()) == [0, 1, 2]
