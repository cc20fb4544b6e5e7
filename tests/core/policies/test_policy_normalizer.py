"""Running observation statistics (ARS V2): merging batches in any split equals the moments of
the concatenation; workers' per-row moments combine to the same bits however rows are split."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from evomotion.core import state
from evomotion.core.policies import normalizer as nz

FLOATS = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)


@st.composite
def chunked(draw):
    """States ``x[n, o]`` and the cut points of a split into chunks (some may be empty)."""
    o = draw(st.integers(1, 4))
    n = draw(st.integers(1, 40))
    x = draw(arrays(np.float64, (n, o), elements=FLOATS))
    cuts = sorted(draw(st.lists(st.integers(0, n), max_size=6)))
    return x, cuts


@settings(max_examples=150, deadline=None, database=None, derandomize=True)
@given(chunked())
def test_merging_chunks_equals_the_concatenation(data) -> None:
    x, cuts = data
    stats = nz.init(x.shape[1])
    for chunk in np.split(x, cuts):
        stats = nz.merge(stats, nz.moments(chunk))
    assert int(stats.count) == x.shape[0]
    scale = 1.0 + np.abs(x).max()
    np.testing.assert_allclose(stats.mean, x.mean(axis=0), rtol=0, atol=1e-12 * scale)
    m2 = ((x - x.mean(axis=0)) ** 2).sum(axis=0)
    np.testing.assert_allclose(stats.m2, m2, rtol=1e-10, atol=1e-12 * scale ** 2 * len(x))
    assert (stats.m2 >= 0).all()
    _, std = nz.mean_std(stats)
    assert (std > 0).all() and np.isfinite(std).all()


@settings(max_examples=100, deadline=None, database=None, derandomize=True)
@given(chunked(), st.integers(1, 5))
def test_rows_combined_in_row_order_give_the_same_bits_for_any_worker_split(data, workers
                                                                             ) -> None:
    x, cuts = data
    rows = x.reshape(x.shape[0], 1, x.shape[1])  # k individuals, 1 step each
    valid = np.ones(rows.shape[:2], dtype=bool)
    whole = nz.update(nz.init(x.shape[1]), rows, valid)
    parts = [nz.moments_per_row(r, v) for r, v in zip(np.array_split(rows, workers),
                                                     np.array_split(valid, workers),
                                                     strict=True)]
    gathered = tuple(np.concatenate([p[i] for p in parts]) for i in range(3))
    split = nz.merge(nz.init(x.shape[1]), nz.combine(*gathered))
    for a, b in ((whole.count, split.count), (whole.mean, split.mean), (whole.m2, split.m2)):
        assert np.array_equal(a, b)


def test_invalid_steps_are_left_out_even_when_nan() -> None:
    rng = np.random.default_rng(0)
    x = rng.normal(size=(3, 5, 2))
    valid = np.ones((3, 5), dtype=bool)
    valid[1, 3:] = False
    x[1, 3:] = np.nan  # a fallen individual's garbage
    s = nz.update(nz.init(2), x, valid)
    kept = x[valid]
    assert int(s.count) == 13
    np.testing.assert_allclose(s.mean, kept.mean(axis=0), atol=1e-14)
    np.testing.assert_allclose(s.m2 / 12, kept.var(axis=0, ddof=1), atol=1e-14)


def test_mean_std_floor_and_sample_std() -> None:
    s = nz.init(3)
    mean, std = nz.mean_std(s)
    assert np.array_equal(mean, np.zeros(3)) and np.array_equal(std, np.ones(3))
    x = np.array([[1.0, 5.0, 0.0], [3.0, 5.0, 1e-12]])
    s = nz.merge(s, nz.moments(x))
    mean, std = nz.mean_std(s)
    np.testing.assert_allclose(mean, [2.0, 5.0, 5e-13])
    assert std[0] == pytest.approx(np.sqrt(2.0))  # sample std (n - 1), as ARS's RunningStat
    assert std[1] == 1.0 and std[2] == 1.0  # below the 1e-8 floor -> 1
    _, std = nz.mean_std(s, std_floor=1e-20)
    assert 0 < std[2] < 1e-11


def test_state_is_immutable_and_checkpoints_as_flat_arrays() -> None:
    s = nz.merge(nz.init(2), nz.moments(np.arange(6.0).reshape(3, 2)))
    arrays, meta = state.state_to_arrays(s)
    assert set(arrays) == {"count", "mean", "m2"} and meta == {}
    back = state.state_from_arrays(nz.RunningStats, arrays, meta)
    assert int(back.count) == 3 and np.array_equal(back.mean, s.mean)
    with pytest.raises(AttributeError):
        s.count = np.array(0)  # type: ignore[misc]


def test_bad_batches_are_one_line_errors() -> None:
    with pytest.raises(ValueError, match="obs_dim"):
        nz.init(0)
    with pytest.raises(ValueError, match="shape"):
        nz.merge(nz.init(2), nz.moments(np.zeros((4, 3))))
    with pytest.raises(ValueError, match="valid"):
        nz.moments(np.zeros((4, 3)), np.ones(5, dtype=bool))
    with pytest.raises(ValueError, match="valid"):
        nz.moments_per_row(np.zeros((2, 3, 1)), np.ones((3, 2), dtype=bool))
