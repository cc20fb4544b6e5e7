"""Paper 001's operators: beta crossover per mode, single-angle mutation, survival, IDEA."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.studies.arm_ik.evolution import (
    active_genes,
    crossover,
    mutate,
    rank_order,
    survivors,
    wrap,
)
from evomotion.studies.arm_ik.kinematics import Layout
from evomotion.studies.arm_ik.scenario import load_scenario, parse_scenario_text

LIMITED = """10
10
5 5
1
1 1
2
2 0 360
1 30 120
1
1 0 360
0
"""


@pytest.fixture
def lay():
    return Layout.of(load_scenario("paper_example"))  # arm 2 genes, fingers 4 genes


def test_modes_select_genes(lay):
    assert active_genes(lay, "arm").tolist() == [True, True] + [False] * 4
    assert active_genes(lay, "fingers").tolist() == [False, False] + [True] * 4
    assert active_genes(lay, "whole").all()


def test_crossover_arm_mode_inherits_fingers_and_blends_by_paper_formula(lay):
    rng = np.random.default_rng(0)
    a = np.full((50, 6), 100.0)
    b = np.full((50, 6), 140.0)
    kids = crossover(a, b, lay, "arm", rng, blend_prob=1.0)
    c1, c2 = kids[:50], kids[50:]
    np.testing.assert_array_equal(c1[:, 2:], a[:, 2:])  # fingers inherited directly
    np.testing.assert_array_equal(c2[:, 2:], b[:, 2:])
    # (a1 + a2 + beta (a1 - a2)) / 2 with beta in [0, 1] -> [100, 120]; sibling mirrored
    assert np.all((c1[:, :2] >= 100) & (c1[:, :2] <= 120))
    np.testing.assert_allclose(c1[:, :2] + c2[:, :2], 240.0)
    kids = crossover(a, b, lay, "fingers", rng, blend_prob=1.0)
    np.testing.assert_array_equal(kids[:50, :2], a[:, :2])


def test_circular_blend_takes_the_short_arc(lay):
    rng = np.random.default_rng(1)
    a = np.full((20, 6), 350.0)
    b = np.full((20, 6), 10.0)
    kids = crossover(a, b, lay, "whole", rng, blend_prob=1.0)
    near_zero = np.minimum(kids, 360 - kids)
    assert np.all(near_zero <= 10 + 1e-9)
    plain = crossover(a, b, lay, "whole", rng, blend_prob=1.0, circular=False)
    assert np.all((plain >= 10) & (plain <= 350)) and np.any(np.abs(plain - 180) < 100)


def test_mutation_changes_one_active_gene_within_limits():
    scn = parse_scenario_text(LIMITED)
    lay = Layout.of(scn)
    rng = np.random.default_rng(2)
    x = np.tile([359.0, 119.0, 5.0], (400, 1))
    y = mutate(x, lay, "arm", rng, rate=1.0, min_deg=1.0, max_deg=60.0)
    changed = y != x
    assert np.all(changed.sum(axis=1) == 1) and not changed[:, 2].any()
    assert np.all((y[:, 0] >= 0) & (y[:, 0] < 360))  # full circle wraps
    assert np.all((y[:, 1] >= 30) & (y[:, 1] <= 120))  # limited joint is clipped
    assert np.any(y[:, 0] < 100)  # some wrapped past 360
    none = mutate(x, lay, "arm", rng, rate=0.0, min_deg=1.0, max_deg=60.0)
    np.testing.assert_array_equal(none, x)


def test_wrap_and_clip():
    lay = Layout.of(parse_scenario_text(LIMITED))
    y = wrap(np.array([[-10.0, 10.0, 725.0]]), lay)
    np.testing.assert_allclose(y, [[350.0, 30.0, 5.0]])


def test_rank_feasible_first_then_objective():
    hits = np.array([0, 2, 0, 1])
    obj = np.array([5.0, 0.1, 3.0, 0.2])
    assert rank_order(hits, obj).tolist() == [1, 3, 0, 2]


def test_survivors_keep_best_no_duplicates_and_idea_fraction():
    rng = np.random.default_rng(3)
    n = 50
    hits = np.r_[np.zeros(80, int), np.ones(20, int)]
    obj = rng.random(100)
    for frac in (0.0, 0.2):
        keep = survivors(hits, obj, n, rng, frac)
        assert keep.size == n and np.unique(keep).size == n
        assert int(np.argmin(np.where(hits == 0, obj, np.inf))) in keep
        if frac:
            assert np.count_nonzero(hits[keep] > 0) >= round(frac * n)


def test_paper_literal_survival_draws_with_replacement():
    rng = np.random.default_rng(5)
    hits, obj = np.zeros(40, int), np.arange(40.0)
    keep = survivors(hits, obj, 20, rng, 0.1, pairwise=False)
    assert keep.size == 20 and keep.max() < 40
    assert np.unique(keep).size < 20 or 39 not in keep  # copies, and the worst never wins
