"""Conformance over every registered operator, plus hypothesis invariants."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from evomotion.core.operators import CROSSOVERS, MUTATIONS, REPLACEMENTS, SELECTIONS
from evomotion.core.operators import crossover as xo
from evomotion.core.operators import mutation as mu
from evomotion.core.operators import selection as sel
from evomotion.core.registry import UnknownNameError, lookup

N, D = 12, 7
LO, HI = np.full(D, -2.0), np.full(D, 3.0)


def _parents(seed=0):
    r = np.random.default_rng(seed)
    return r.uniform(LO, HI, (N, D)), r.uniform(LO, HI, (N, D))


@pytest.mark.parametrize("name", sorted(CROSSOVERS))
def test_crossover_conformance(name):
    a, b = _parents()
    out1 = CROSSOVERS[name](a, b, np.random.default_rng(5))
    out2 = CROSSOVERS[name](a, b, np.random.default_rng(5))
    k = 3 if name == "linear" else 2
    assert out1.shape == (k, N, D)
    assert np.all(np.isfinite(out1))
    np.testing.assert_array_equal(out1, out2)  # deterministic for a seed
    a0, b0 = _parents()
    np.testing.assert_array_equal(a, a0)  # parents untouched
    np.testing.assert_array_equal(b, b0)


@pytest.mark.parametrize("name", sorted(MUTATIONS))
def test_mutation_conformance(name):
    a, _ = _parents()
    out1 = MUTATIONS[name](a, LO, HI, np.random.default_rng(1), 0.5)
    out2 = MUTATIONS[name](a, LO, HI, np.random.default_rng(1), 0.5)
    assert out1.shape == a.shape
    assert np.all((out1 >= LO) & (out1 <= HI))
    np.testing.assert_array_equal(out1, out2)
    assert not np.array_equal(out1, a)  # rate 0.5 over 12 individuals changes something
    same = MUTATIONS[name](a, LO, HI, np.random.default_rng(1), 0.0)
    np.testing.assert_array_equal(same, a)


@pytest.mark.parametrize("name", sorted(SELECTIONS))
def test_selection_conformance(name):
    cost = np.array([3.0, 1.0, np.inf, -2.0, 1.0, 7.0])
    i1 = SELECTIONS[name](cost, 500, np.random.default_rng(2))
    i2 = SELECTIONS[name](cost, 500, np.random.default_rng(2))
    assert i1.shape == (500,) and i1.dtype.kind == "i"
    assert i1.min() >= 0 and i1.max() < cost.size
    np.testing.assert_array_equal(i1, i2)
    counts = np.bincount(i1, minlength=cost.size)
    assert counts[3] > counts[5]  # the best is chosen more often than the worst finite one
    assert counts[2] <= counts[3]


@pytest.mark.parametrize("name", sorted(REPLACEMENTS))
def test_replacement_conformance(name):
    r = np.random.default_rng(0)
    pop, kids = r.random((6, 3)), r.random((6, 3))
    cost, kcost = r.random(6), r.random(6)
    new, ncost = REPLACEMENTS[name](pop, cost, kids, kcost, 2)
    assert new.shape == pop.shape and ncost.shape == cost.shape
    assert ncost.min() == min(cost.min(), kcost.min()) or name == "generational"
    assert cost.min() in ncost  # the best parent always survives (elites or plus)


def test_unknown_name_message():
    with pytest.raises(UnknownNameError, match="unknown crossover 'blx'; available: .*blx_alpha"):
        lookup(CROSSOVERS, "crossover", "blx")


floats = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)
pair = st.integers(1, 6).flatmap(
    lambda d: st.tuples(arrays(float, (4, d), elements=floats), arrays(float, (4, d),
                        elements=floats)))


@settings(max_examples=60, deadline=None)
@given(pair, st.floats(0, 1.5), st.integers(0, 2**32 - 1))
def test_blx_alpha_interval(ab, alpha, seed):
    a, b = ab
    kids = xo.blx_alpha(a, b, np.random.default_rng(seed), alpha=alpha)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    d = hi - lo
    tol = 1e-9 * (1 + np.abs(lo) + np.abs(hi))
    assert np.all(kids >= lo - alpha * d - tol) and np.all(kids <= hi + alpha * d + tol)


@settings(max_examples=60, deadline=None)
@given(pair, st.integers(0, 2**32 - 1))
def test_arithmetic_children_are_convex_combinations(ab, seed):
    a, b = ab
    for fn in (xo.arithmetic_whole, xo.arithmetic_single, xo.beta_blend):
        kids = fn(a, b, np.random.default_rng(seed))
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        tol = 1e-9 * (1 + np.abs(lo) + np.abs(hi))
        assert np.all(kids >= lo - tol) and np.all(kids <= hi + tol)
        np.testing.assert_allclose(kids[0] + kids[1], a + b, rtol=1e-9, atol=1e-6)


@settings(max_examples=60, deadline=None)
@given(pair, st.integers(0, 2**32 - 1))
def test_swapping_crossovers_preserve_genes(ab, seed):
    a, b = ab
    for fn in (xo.one_point, xo.two_point, xo.uniform):
        c1, c2 = fn(a, b, np.random.default_rng(seed))
        from_a = c1 == a
        assert np.all(from_a | (c1 == b))
        assert np.all(np.where(from_a & (a != b), c2 == b, True))


@settings(max_examples=40, deadline=None)
@given(pair)
def test_linear_crossover_three_children(ab):
    a, b = ab
    m, c1, c2 = xo.linear(a, b, np.random.default_rng(0))
    np.testing.assert_allclose(m, (a + b) / 2)
    np.testing.assert_allclose(c1 + c2, a + b, atol=1e-6)


@settings(max_examples=40, deadline=None)
@given(arrays(float, (5, 3), elements=st.floats(0.01, 100)),
       arrays(float, (5, 3), elements=st.floats(0.01, 100)), st.integers(0, 1000))
def test_geometric_positive_genes_within_parents(a, b, seed):
    kids = xo.geometric(a, b, np.random.default_rng(seed))
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    assert np.all(kids >= lo * (1 - 1e-9)) and np.all(kids <= hi * (1 + 1e-9))
    np.testing.assert_allclose(kids[0] * kids[1], a * b, rtol=1e-9)


def test_geometric_mixed_signs_falls_back_to_arithmetic():
    a, b = np.array([[-1.0, 2.0]]), np.array([[3.0, 0.0]])
    kids = xo.geometric(a, b, np.random.default_rng(0))
    assert np.all(np.isfinite(kids))
    assert -1.0 <= kids[0, 0, 0] <= 3.0


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 7), st.floats(0.001, 0.5), st.integers(0, 1000))
def test_perturb_k_changes_at_most_k_genes(k, delta, seed):
    x = np.random.default_rng(seed).uniform(LO, HI, (N, D))
    y = mu.perturb_k(x, LO, HI, np.random.default_rng(seed + 1), 1.0, k=k, delta=delta)
    changed = (y != x).sum(axis=1)
    assert np.all(changed <= k)
    assert np.all(np.abs(y - x) <= delta * (HI - LO) + 1e-12)


@settings(max_examples=40, deadline=None)
@given(arrays(float, 8, elements=st.floats(-1e6, 1e6)), st.integers(0, 1000))
def test_roulette_safe_for_any_costs(cost, seed):
    idx = sel.roulette(cost, 50, np.random.default_rng(seed))
    assert idx.min() >= 0 and idx.max() < 8


def test_roulette_equal_costs_uniform():
    idx = sel.roulette(np.ones(4), 4000, np.random.default_rng(0))
    counts = np.bincount(idx, minlength=4)
    assert np.all(np.abs(counts - 1000) < 150)


def test_tournament_k1_is_uniform_and_large_k_picks_best():
    cost = np.arange(10.0)
    assert np.all(sel.tournament(cost, 50, np.random.default_rng(0), k=200) == 0)
    counts = np.bincount(sel.tournament(cost, 5000, np.random.default_rng(0), k=1), minlength=10)
    assert counts.min() > 350
