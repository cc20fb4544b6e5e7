"""The repertoire heat map's cells (issue 35): fallen elites told apart from standing ones, the
colour scale over the standing cells only, tooltips with labels and units, a click on a cell
without a motion answered."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from evomotion.studio import archive_map as amap


def _archive(objective, measures, cells):
    """A 2 x 2 x 2 grid over dx, dy, dtheta with the given elites."""
    lower, upper, bins = np.array([-1.0, -1.0, -10.0]), np.array([1.0, 1.0, 10.0]), [2, 2, 2]
    measures = np.asarray(measures, float)
    centre = np.stack([lower + (np.clip(((m - lower) / (upper - lower) * bins).astype(int), 0, 1)
                                + 0.5) * (upper - lower) / bins for m in measures])
    return SimpleNamespace(kind="grid", bins=np.array(bins), cells=8, lower=lower, upper=upper,
                           measure_names=("dx_m", "dy_m", "dtheta_deg"),
                           cell=np.array(cells), centre=centre,
                           objective=np.asarray(objective, float), measures=measures)


def test_fallen_standing_and_playable_are_told_apart_and_counted_as_the_cli_does():
    a = _archive([-0.2, -9.5, -0.4, -0.1],
                 [[0.5, 0.5, 5], [-0.5, 0.5, 5], [0.5, -0.5, -5], [-0.5, -0.5, -5]], [7, 3, 4, 0])
    cells = amap.map_cells(a, playable={7, 4}, fallen_at=-9.0)
    state = {m.cell: m.state for m in cells}
    assert state == {7: amap.PLAYABLE, 3: amap.FELL, 4: amap.PLAYABLE, 0: amap.STANDING}
    text = amap.counts_text(a, {7, 4}, -9.0)
    assert "4 of 8 cells filled" in text and "2 standing steps with a motion" in text
    assert "1 standing outside the measure box" in text and "1 fell" in text


def test_colour_scale_spans_the_standing_cells_only():
    a = _archive([-0.2, -9.5, -0.4], [[0.5, 0.5, 5], [-0.5, 0.5, 5], [0.5, -0.5, -5]],
                 [7, 3, 4])
    cells = amap.map_cells(a, {7, 4}, -9.0)
    lo, hi = amap.colour_range(cells)
    assert hi == pytest.approx(-0.2) and -0.4 <= lo < hi  # not -9.5 ... -0
    standing, fell = amap.series(cells)
    assert [d["cell"] for d in fell["data"]] == [3]
    assert sorted(d["cell"] for d in standing["data"]) == [4, 7]


def test_the_best_elite_of_a_bin_is_shown_and_slices_pick_the_third_measure():
    a = _archive([-0.5, -0.1], [[0.5, 0.5, 5], [0.5, 0.5, -5]], [7, 6])
    assert [m.cell for m in amap.map_cells(a, set(), -9.0)] == [6]
    assert [m.cell for m in amap.map_cells(a, set(), -9.0, slice_k=1)] == [7]


def test_tooltip_names_measures_with_units_objective_and_state():
    a = _archive([-0.0125], [[0.0512, -0.793, 3.14159]], [7])
    (m,) = amap.map_cells(a, {7}, -9.0)
    assert m.tip == "cell 0007: dx 0.0512 m, dy -0.793 m, dθ 3.14°; objective -0.0125; playable"
    assert amap.axis_name("dtheta_deg") == "dθ (°)" and amap.axis_name("energy") == "energy"


def test_a_click_on_a_cell_without_a_motion_says_why():
    a = _archive([-9.5, -0.3], [[0.5, 0.5, 5], [-0.5, 0.5, 5]], [7, 3])
    by_cell = {m.cell: m for m in amap.map_cells(a, set(), -9.0)}
    assert "fell" in amap.click_message(by_cell[7])
    assert "outside the measure box" in amap.click_message(by_cell[3])
    assert amap.click_message(None) == ""
