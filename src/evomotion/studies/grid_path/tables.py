"""Segment tables for the discrete encoding: exact validity and length by lookup.

In ``discrete`` mode every waypoint is the centre of a cell touched by its perpendicular, and
segments only join consecutive layers (S, the cells of L_1, ..., the cells of L_{n-1}, G).
So all possible segments can be tested once, exactly, with :func:`~.geometry.segments_valid`,
and a batch of chromosomes is then evaluated by gathering from two flat arrays. Layer cells
are all closed cells the perpendicular touches, so the cell of any point on it is listed.
"""

from __future__ import annotations

import numpy as np

from evomotion.studies.grid_path.encoding import PerpendicularEncoding
from evomotion.studies.grid_path.geometry import segments_valid

MAX_PAIRS = 400_000  # above this, evaluate segments geometrically instead


def _touched_cells(a: np.ndarray, b: np.ndarray, w: int, h: int) -> np.ndarray:
    """Cell ids ``y * w + x`` of the closed cells that segment ``a -> b`` touches."""
    d = b - a
    ts = [0.0, 1.0]
    for ax in (0, 1):
        if d[ax] != 0:
            lo, hi = sorted((a[ax], b[ax]))
            ks = np.arange(np.ceil(lo), np.floor(hi) + 1)
            ts.extend(((ks - a[ax]) / d[ax]).tolist())
    t = np.unique(np.clip(ts, 0, 1))
    t = np.concatenate([t, 0.5 * (t[1:] + t[:-1])])
    p = a + t[:, None] * d
    cells: set[int] = set()
    for x, y in p.tolist():
        xs = {int(np.floor(x)), int(np.floor(x - 1e-9))}
        ys = {int(np.floor(y)), int(np.floor(y - 1e-9))}
        cells.update(cy * w + cx for cx in xs for cy in ys if 0 <= cx < w and 0 <= cy < h)
    return np.array(sorted(cells), dtype=np.int64)


class SegmentTables:
    """Validity and length of every segment between consecutive layers."""

    def __init__(self, enc: PerpendicularEncoding, blocked: np.ndarray, rule: str) -> None:
        h, w = blocked.shape
        self.w = w
        feet, nrm = enc.foot_points(), enc.normal
        layers = [np.array([-1])]
        self.lookup = np.full((enc.dim + 2, w * h), -1, dtype=np.int64)
        for g in range(enc.dim):
            cells = _touched_cells(feet[g] + enc.lower[g] * nrm, feet[g] + enc.upper[g] * nrm,
                                   w, h)
            layers.append(cells)
            self.lookup[g + 1, cells] = np.arange(cells.size)
        layers.append(np.array([-1]))
        self.lookup[0] = self.lookup[-1] = 0  # S and G: the only point of their layer
        self.sizes = np.array([len(c) for c in layers])
        pts = [enc.start[None]] + [np.stack([c % w, c // w], 1) + 0.5 for c in layers[1:-1]] \
            + [enc.goal[None]]
        pair = self.sizes[:-1] * self.sizes[1:]
        self.offset = np.concatenate([[0], np.cumsum(pair)[:-1]])
        a = np.concatenate([np.repeat(pts[i], self.sizes[i + 1], 0) for i in range(len(pair))])
        b = np.concatenate([np.tile(pts[i + 1], (self.sizes[i], 1)) for i in range(len(pair))])
        self.valid = segments_valid(blocked, a, b, rule)
        self.length = np.hypot(*(b - a).T)
        self.h = h
        self._size = np.array([w, h], dtype=float)  # x < w and y < h on the map
        self._feet, self._normal = feet, nrm
        self._inner = self.lookup[1:enc.dim + 1]  # layers of the genes
        self._gene_rows = np.arange(enc.dim)
        self._seg_offset = self.offset  # first pair of segment s (layer s -> s + 1)
        self._seg_next = self.sizes[1:]  # size of the layer a segment ends in

    def gene_cells(self, genes: np.ndarray) -> np.ndarray | None:
        """Position of each gene's cell in its layer, ``idx[P, d]``, straight from the genes
        (the cell of ``foot + y * normal``, as :meth:`.PerpendicularEncoding.decode` snaps
        it), or ``None`` when a cell is off the map or not listed."""
        # this runs twice per batch (mutation, evaluation): few numpy calls, no wrappers
        xy = self._feet + genes[..., None] * self._normal
        np.floor(xy, out=xy)
        on_map = (xy >= 0.0) & (xy < self._size)
        if np.count_nonzero(on_map) != on_map.size:  # off the map (or NaN)
            return None
        ix = xy.astype(np.int64)
        idx = self._inner[self._gene_rows, ix[..., 1] * self.w + ix[..., 0]]
        return None if np.count_nonzero(idx < 0) else idx

    def chromosomes(self, genes: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """``(valid[P, S], length[P, S])`` of the decoded polylines of ``genes[P, d]`` (the
        same values as :meth:`polylines` of the decoded points), or ``None`` (see
        :meth:`gene_cells`)."""
        idx = self.gene_cells(genes)
        if idx is None:
            return None
        full = np.zeros((idx.shape[0], idx.shape[1] + 2), dtype=np.int64)  # S and G: 0
        full[:, 1:-1] = idx
        flat = self._seg_offset + full[:, :-1] * self._seg_next + full[:, 1:]
        return self.valid[flat], self.length[flat]

    @staticmethod
    def feasible(enc: PerpendicularEncoding, blocked: np.ndarray) -> bool:
        """Whether the tables stay small (a rough bound from the perpendiculars' lengths)."""
        k = 2.0 * (enc.upper - enc.lower) + 4.0
        return float((k[:-1] * k[1:]).sum() + 2 * k.max()) <= MAX_PAIRS

    def index(self, layer: np.ndarray, xy: np.ndarray) -> np.ndarray:
        """Position of each point's cell in its layer (0 for S and G; -1 if not listed)."""
        # points of the encoding lie inside the map (x, y >= 0), so truncation is floor
        cell = xy[..., 1].astype(np.int64) * self.w + xy[..., 0].astype(np.int64)
        return self.lookup[layer, cell]

    def pairs(self, layer: np.ndarray, a: np.ndarray, b: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
        """``(valid, length)`` of segments from index ``a`` in ``layer`` to ``b`` in the next."""
        flat = self.offset[layer] + a * self.sizes[layer + 1] + b
        return self.valid[flat], self.length[flat]

    def polylines(self, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """``(valid[P, S], length[P, S])`` of discrete polylines ``pts[P, n+1, 2]``, or
        ``None`` when a point's cell is not in its layer (then use the geometry)."""
        h = self.lookup.shape[1] // self.w
        if pts.min() < 0 or pts[..., 0].max() >= self.w or pts[..., 1].max() >= h:
            return None  # off-map points (genes outside their bounds): use the geometry
        n_layers = pts.shape[1]
        layer = np.broadcast_to(np.arange(n_layers), pts.shape[:2])
        idx = self.index(layer, pts)
        if (idx < 0).any():
            return None
        return self.pairs(layer[:, :-1], idx[:, :-1], idx[:, 1:])
