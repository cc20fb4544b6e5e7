"""Grid and CVT archives: cells, insertion rules, CMA-MAE thresholds, statistics."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.core.archives import IMPROVED, NEW_CELL, NOT_ADDED, ArchiveSpec, add, stats

GRID = ArchiveSpec("grid", np.array([0.0, -1.0]), np.array([1.0, 1.0]), bins=(4, 2))


def test_grid_cells_and_clipping():
    s = GRID.init(np.random.default_rng(0), 3)
    m = np.array([[0.0, -1.0], [0.99, 0.99], [0.3, 0.5], [-5.0, 9.0], [1.0, 1.0]])
    np.testing.assert_array_equal(GRID.index(s, m), [0, 7, 3, 1, 7])
    centres = GRID.cell_centres(s)
    assert centres.shape == (8, 2)
    np.testing.assert_array_equal(GRID.index(s, centres), np.arange(8))


def test_add_new_improve_reject_and_best_of_a_batch():
    s = GRID.init(np.random.default_rng(0), 1)
    x = np.arange(5.0)[:, None]
    m = np.array([[0.1, 0.1]] * 3 + [[0.9, -0.9], [0.9, -0.9]])
    s1, status, value = add(GRID, s, x, np.array([1.0, 3.0, 2.0, np.nan, 5.0]), m)
    # cell of rows 0-2: all new; the best (row 1) is the elite; row 3 is NaN: never added
    np.testing.assert_array_equal(status, [NEW_CELL, NEW_CELL, NEW_CELL, NOT_ADDED, NEW_CELL])
    c = GRID.index(s1, m[:1])[0]
    assert s1.solutions[c, 0] == 1.0 and s1.objective[c] == 3.0
    assert s1.occupied.sum() == 2 and not s.occupied.any()  # the old state is untouched
    s2, status, value = add(GRID, s1, x[:2], np.array([2.5, 4.0]), m[:2])
    np.testing.assert_array_equal(status, [NOT_ADDED, IMPROVED])
    np.testing.assert_allclose(value, [-0.5, 1.0])
    assert s2.objective[c] == 4.0 and s2.solutions[c, 0] == 1.0


def test_cma_mae_threshold_moves_towards_each_accepted_objective_in_turn():
    s = GRID.init(np.random.default_rng(0), 1, threshold_min=0.0)
    m = np.array([[0.1, 0.1]] * 3)
    f = np.array([3.0, 1.0, 2.0])
    alpha = 0.1
    s1, status, value = add(GRID, s, np.zeros((3, 1)), f, m, alpha)
    assert (status == NEW_CELL).all()
    np.testing.assert_allclose(value, f)  # f - threshold_min (0)
    t = 0.0
    for fi in sorted(f):  # ascending, sequentially
        t = (1 - alpha) * t + alpha * fi
    c = GRID.index(s1, m[:1])[0]
    assert np.isclose(s1.threshold[c], t)
    assert s1.objective[c] == 3.0
    s2, status, _ = add(GRID, s1, np.zeros((1, 1)), np.array([t + 0.01]), m[:1], alpha)
    assert status[0] == IMPROVED and s2.objective[c] == t + 0.01  # a worse elite may replace


def test_cvt_is_deterministic_from_the_seed_and_covers_the_box():
    spec = ArchiveSpec("cvt", np.zeros(2), np.ones(2), cells_cvt=50, samples=5000)
    a = spec.init(np.random.default_rng(7), 2)
    b = spec.init(np.random.default_rng(7), 2)
    c = spec.init(np.random.default_rng(8), 2)
    np.testing.assert_array_equal(a.centroids, b.centroids)
    assert not np.array_equal(a.centroids, c.centroids)
    assert a.centroids.shape == (50, 2) and (a.centroids >= 0).all() and (a.centroids <= 1).all()
    np.testing.assert_array_equal(spec.index(a, a.centroids), np.arange(50))
    # Lloyd's iterations spread the cells: every one holds some of a fine uniform sample
    pts = np.random.default_rng(1).uniform(0, 1, (20000, 2))
    counts = np.bincount(spec.index(a, pts), minlength=50)
    assert counts.min() > 0.3 * counts.mean()


def test_stats():
    s = GRID.init(np.random.default_rng(0), 1)
    assert stats(s)["archive_size"] == 0 and np.isnan(stats(s)["qd_best"])
    s, _, _ = add(GRID, s, np.zeros((2, 1)), np.array([1.0, 2.0]),
                  np.array([[0.1, 0.1], [0.9, 0.9]]))
    out = stats(s, offset=-1.0)
    assert out == {"archive_size": 2, "coverage": 0.25, "qd_score": 5.0, "qd_best": 2.0}


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(-2, 2), st.floats(-2, 2), st.floats(-10, 10)),
                min_size=1, max_size=40), st.integers(1, 4))
def test_elitist_archive_only_improves(points, batches):
    """Whatever is added, in whatever batches: no cell empties, no elite gets worse, and
    every cell holds the best objective that fell into it."""
    s = GRID.init(np.random.default_rng(0), 1)
    arr = np.array(points)
    best: dict[int, float] = {}
    for chunk in np.array_split(arr, batches):
        if not len(chunk):
            continue
        before = s
        s, status, _ = add(GRID, s, chunk[:, :1], chunk[:, 2], chunk[:, :2])
        assert (s.occupied >= before.occupied).all()
        assert (s.objective[before.occupied] >= before.objective[before.occupied]).all()
        for c, f in zip(GRID.index(s, chunk[:, :2]), chunk[:, 2], strict=True):
            best[int(c)] = max(best.get(int(c), -np.inf), f)
    for c, f in best.items():
        assert s.objective[c] == f
    assert s.occupied.sum() == len(best)
