"""The quality-diversity archive's heat map on a run's page (the study's ``archive_map`` view).

One square per (x, y) bin of a grid archive: the best elite over the other measures (or of
one slice of the third). What a cell holds is told apart, as the study's own CLI counts it:

- **playable**: its motion was exported (``repertoire/cell-NNNN.motion``); a click plays it;
- **standing, not exported**: the elite stays up but its measured behaviour lies outside the
  archive's box (a grid keeps such behaviour in its edge cells; the study does not export it);
- **fell**: the elite's objective is at or below the study's
  :attr:`~evomotion.studies.view.StudyView.archive_fallen_at` (drawn grey, outside the colour
  scale, which spans the standing cells only).

A click on a cell without a motion says why in a line under the map; the tooltip gives the
cell, the elite's measured behaviour with units, its objective and what the cell holds.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

#: unit suffixes of measure names (``dx_m``) and how a value is written with them
UNITS = {"m": " m", "deg": "°", "rad": " rad", "s": " s", "j": " J", "n": " N"}
FELL, STANDING, PLAYABLE = "fell", "standing, outside the measure box (not exported)", "playable"


def _split(name: str) -> tuple[str, str]:
    base, _, unit = name.rpartition("_")
    if not base or unit.lower() not in UNITS:
        return name.replace("theta", "θ"), ""
    return base.replace("theta", "θ"), UNITS[unit.lower()]


def measure_text(name: str, value: float) -> str:
    """``dx_m``, 0.0512 -> ``dx 0.0512 m``; ``dtheta_deg`` -> ``dθ 3.1°``."""
    base, unit = _split(name)
    return f"{base} {value:.3g}{unit}"


def axis_name(name: str) -> str:
    """``dx_m`` -> ``dx (m)``; a name without a unit suffix as it is."""
    base, unit = _split(name)
    return f"{base} ({unit.strip()})" if unit else base


@dataclass(frozen=True)
class MapCell:
    """One square of the map: its bin, the elite shown there and what it holds."""

    ix: int
    iy: int
    cell: int
    objective: float
    state: str  # PLAYABLE, STANDING or FELL
    tip: str

    def item(self) -> dict[str, Any]:
        """The ECharts heat-map data item (the tooltip reads ``tip``)."""
        return {"value": [self.ix, self.iy, round(self.objective, 4)], "cell": self.cell,
                "tip": self.tip}


def bin_index(a: Any) -> np.ndarray:
    """``int[n, m]``: each elite's bin along every measure (from its cell's centre)."""
    lo, hi = a.lower, a.upper
    bins = [int(b) for b in a.bins]
    return np.stack([np.clip(((a.centre[:, d] - lo[d]) / (hi[d] - lo[d]) * bins[d])
                             .astype(int), 0, bins[d] - 1) for d in range(len(bins))], 1)


def map_cells(a: Any, playable: set[int], fallen_at: float | None,
              slice_k: int | None = None) -> list[MapCell]:
    """The squares of the map, sorted by bin: per (x, y) bin the elite of highest objective
    (over the other measures, or only those in bin ``slice_k`` of the third measure)."""
    idx = bin_index(a)
    best: dict[tuple[int, int], int] = {}
    for k in range(len(a.cell)):
        if slice_k is not None and len(a.bins) > 2 and idx[k, 2] != slice_k:
            continue
        key = (int(idx[k, 0]), int(idx[k, 1]))
        if key not in best or a.objective[k] > a.objective[best[key]]:
            best[key] = k
    out = []
    for key in sorted(best):
        k = best[key]
        c, o = int(a.cell[k]), float(a.objective[k])
        state = FELL if fallen_at is not None and o <= fallen_at else \
            PLAYABLE if c in playable else STANDING
        measured = ", ".join(measure_text(n, float(v))
                             for n, v in zip(a.measure_names, a.measures[k], strict=True))
        tip = f"cell {c:04d}: {measured}; objective {o:.4g}; {state}"
        out.append(MapCell(key[0], key[1], c, o, state, tip))
    return out


def counts_text(a: Any, playable: set[int], fallen_at: float | None) -> str:
    """The map's headline, counting elites as the study's CLI does."""
    cells = [int(c) for c in a.cell]
    fell = 0 if fallen_at is None else int(np.sum(a.objective <= fallen_at))
    up = len(cells) - fell
    exported = sum(c in playable for c in cells)
    text = f"repertoire: {len(cells)} of {a.cells} cells filled"
    if fallen_at is None:
        return f"{text}, {exported} with a motion; click a cell to play it"
    return (f"{text}: {exported} standing steps with a motion (click to play), "
            f"{up - exported} standing outside the measure box, {fell} fell (grey)")


def colour_range(cells: list[MapCell]) -> tuple[float, float]:
    """The colour scale over the standing cells (5th percentile to the best): a fallen
    cell's penalty no longer stretches it until every standing cell has one colour."""
    up = np.array([m.objective for m in cells if m.state != FELL])
    if not up.size:
        return 0.0, 1.0
    lo, hi = float(np.percentile(up, 5)), float(up.max())
    return (lo, hi) if hi > lo else (lo, lo + 1.0)


def series(cells: list[MapCell]) -> list[dict[str, Any]]:
    """Two heat-map series: the standing cells (coloured by the visual map) and the fallen
    ones (grey, outside it)."""
    return [{"type": "heatmap", "name": "standing",
             "data": [m.item() for m in cells if m.state != FELL]},
            {"type": "heatmap", "name": "fell", "itemStyle": {"color": "#9e9e9e"},
             "data": [m.item() for m in cells if m.state == FELL]}]


def click_message(cell: MapCell | None) -> str:
    """What a click on a square says when it plays nothing (empty when it plays)."""
    if cell is None or cell.state == PLAYABLE:
        return ""
    if cell.state == FELL:
        return f"cell {cell.cell:04d}: its step fell (objective {cell.objective:.4g}): no motion"
    return f"cell {cell.cell:04d}: standing, but outside the measure box: not exported"
