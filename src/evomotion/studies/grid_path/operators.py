"""The paper's validity-keeping path operators on the perpendicular encoding.

Zhang et al. (2014, sec. 3.1 and 3.2.3):

- initial paths: each P_i is drawn as a random *free* cell on its perpendicular L_i, and
  re-drawn while the segment from P_{i-1} crosses an obstacle ("重新生成下一柵格,繼續判斷
  直至路徑有效"); we bound the re-draws (``retries``) and restart paths whose last segment
  into G stays invalid (``restarts``); a path still invalid then keeps its penalty;
- mutation: pick one path point at random (the start point leaves the path unchanged),
  replace it by a free position on its perpendicular, and repeat while the path is invalid
  (bounded by ``retries``; on failure the point is left as it was).

Everything is vectorised over the individuals; the loops run over genes and retries. The
initialisation draws the re-draws in batches of 2, 4, 8, ... (most succeed at once); the
mutation, called on a few rows per cGA wave, draws all ``retries`` at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evomotion.studies.grid_path.encoding import PerpendicularEncoding
from evomotion.studies.grid_path.geometry import segments_valid
from evomotion.studies.grid_path.tables import SegmentTables


def free_pieces(enc: PerpendicularEncoding, blocked: np.ndarray) -> tuple[np.ndarray, ...]:
    """Free stretches of every perpendicular: ``lo[g, K]``, ``hi[g, K]``, ``count[g]``.

    Each stretch is the part of L_g inside one free cell, as an interval of y'.
    """
    feet, nrm = enc.foot_points(), enc.normal
    pieces: list[list[tuple[float, float]]] = []
    h, w = blocked.shape
    for g in range(enc.dim):
        a, b = enc.lower[g], enc.upper[g]
        at = [a, b]
        for axis in (0, 1):
            if abs(nrm[axis]) > 1e-15:
                v0, v1 = sorted((feet[g, axis] + a * nrm[axis], feet[g, axis] + b * nrm[axis]))
                ks = np.arange(np.ceil(v0), np.floor(v1) + 1)
                at.extend(((ks - feet[g, axis]) / nrm[axis]).tolist())
        cuts = np.unique(np.clip(at, a, b))
        mids = 0.5 * (cuts[1:] + cuts[:-1])
        cells = np.floor(feet[g] + mids[:, None] * nrm).astype(int)
        inside = (cells[:, 0] >= 0) & (cells[:, 0] < w) & (cells[:, 1] >= 0) & (cells[:, 1] < h)
        ok = inside & (cuts[1:] > cuts[:-1])
        ok[ok] &= ~blocked[cells[ok, 1], cells[ok, 0]]
        pieces.append(list(zip(cuts[:-1][ok], cuts[1:][ok], strict=True)))
    k = max(1, max(len(p) for p in pieces))
    lo = np.zeros((enc.dim, k))
    hi = np.zeros((enc.dim, k))
    count = np.array([len(p) for p in pieces])
    for g, p in enumerate(pieces):
        if p:
            lo[g, :len(p)], hi[g, :len(p)] = np.array(p).T
        else:  # fully blocked perpendicular: fall back to its whole extent
            lo[g, 0], hi[g, 0], count[g] = enc.lower[g], enc.upper[g], 1
    return lo, hi, count


def _stages(total: int) -> list[int]:
    """Batch sizes 2, 4, 8, ... adding up to ``total`` re-draws."""
    out, k = [], 2
    while total > 0:
        out.append(min(k, total))
        total -= out[-1]
        k *= 2
    return out


@dataclass
class PathOperators:
    """The paper's initialisation and mutation for one map, encoding and validity rule."""

    enc: PerpendicularEncoding
    blocked: np.ndarray
    rule: str
    retries: int = 20
    restarts: int = 5
    tables: SegmentTables | None = None  # discrete mode: exact validity by lookup

    def __post_init__(self) -> None:
        self.lo, self.hi, self.count = free_pieces(self.enc, self.blocked)
        self.piece_cell = self._piece_cells()
        t = self.tables  # per gene g: table offset and layer size of the segments in and out
        self._gene_pairs = None if t is None else (
            t.offset[:-1], t.sizes[1:-1], t.offset[1:], t.sizes[2:])

    def _piece_cells(self) -> np.ndarray | None:
        """Table position ``[g, j]`` of the cell of free stretch ``j`` of perpendicular ``g``,
        when every point :meth:`draw` can pick in every stretch lies in that one cell, else
        ``None``. ``floor(foot + y * normal)`` is monotone in ``y`` in floating point, so
        checking both ends of the drawn range (widened a little) proves it for all draws."""
        t = self.tables
        if t is None:
            return None
        g = np.repeat(np.arange(self.enc.dim), self.count)
        j = np.concatenate([np.arange(c) for c in self.count])
        ends = []
        for u in (0.0499, 0.9501):
            y = self.lo[g, j] + (self.hi[g, j] - self.lo[g, j]) * u
            ends.append(np.floor(self.enc.foot_points()[g] + y[:, None] * self.enc.normal))
        xy = ends[0]
        if (ends[0] != ends[1]).any() or xy.min() < 0 or xy[:, 0].max() >= t.w \
                or xy[:, 1].max() >= t.h:
            return None
        idx = t.index(g + 1, xy)
        if (idx < 0).any():
            return None
        out = np.full(self.lo.shape, -1, dtype=np.int64)
        out[g, j] = idx
        return out

    def _seg_ok(self, layer: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Validity of segments ``a[k] -> b[k]`` from ``layer[k]`` to the next layer."""
        t = self.tables
        if t is not None and min(a.min(), b.min()) >= 0 and max(a[:, 0].max(), b[:, 0].max()) < t.w:
            h = t.lookup.shape[1] // t.w
            if max(a[:, 1].max(), b[:, 1].max()) < h:
                ia, ib = t.index(layer, a), t.index(layer + 1, b)
                if (ia >= 0).all() and (ib >= 0).all():
                    return t.pairs(layer, ia, ib)[0]
        return segments_valid(self.blocked, a, b, self.rule)

    def _layer_index(self, layer: np.ndarray, xy: np.ndarray) -> np.ndarray | None:
        """Positions of points ``xy[k]`` in the table layers ``layer[k]``, or ``None`` when a
        point is off the map or not listed (then :meth:`_seg_ok` decides by geometry)."""
        t = self.tables
        if t is None or xy.min() < 0 or xy[:, 0].max() >= t.w or xy[:, 1].max() >= t.h:
            return None
        idx = t.index(layer, xy)
        return idx if (idx >= 0).all() else None

    def draw(self, genes: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """A random free position y' on each perpendicular ``genes[k]`` (a free cell chosen
        uniformly, then a uniform point inside its stretch, strictly inside it)."""
        return self._draw(genes, rng)[0]

    def _draw(self, genes: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, ...]:
        """:meth:`draw` and the stretch index ``j`` of each draw."""
        u = rng.random((2, genes.size))
        j = (u[0] * self.count[genes]).astype(int)
        lo, hi = self.lo[genes, j], self.hi[genes, j]
        return lo + (hi - lo) * (0.05 + 0.9 * u[1]), j

    def _first_valid_cells(self, genes: np.ndarray, ia: np.ndarray, ib: np.ndarray,
                           rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`_first_valid` (with a right end, all ``retries`` drawn at once) by table
        lookups only: ``ia``/``ib`` are the table positions of the end points, the drawn
        cell comes from :attr:`piece_cell`. The same draws, so the same result where a
        valid position is found (elsewhere the returned ``y`` is not used)."""
        t, R, n = self.tables, self.retries, genes.size
        piece_cell, gene_pairs = self.piece_cell, self._gene_pairs
        # discrete mode only: the tables, their stretch cells and gene pairs are all set
        assert t is not None and piece_cell is not None and gene_pairs is not None
        gr = genes.repeat(R)
        y, j = self._draw(gr, rng)
        ip = piece_cell[gr, j]
        in_off, in_mul, out_off, out_mul = gene_pairs
        into = (in_off[genes] + ia * in_mul[genes]).repeat(R)  # segment in: + drawn position
        out = (out_off[genes] + ib).repeat(R)  # segment out: + drawn position * out_mul
        ok = t.valid[into + ip] & t.valid[out + ip * out_mul[gr]]
        ok = ok.reshape(n, R)
        return y.reshape(n, R)[np.arange(n), ok.argmax(1)], ok.any(1)

    def _point(self, genes: np.ndarray, y: np.ndarray) -> np.ndarray:
        return self.enc.snap(self.enc.foot_points()[genes] + y[:, None] * self.enc.normal)

    def _first_valid(self, genes: np.ndarray, left: np.ndarray, right: np.ndarray | None,
                     rng: np.random.Generator,
                     stages: list[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Up to ``retries`` free positions on perpendicular ``genes[k]``; the first whose
        segments from ``left[k]`` (and to ``right[k]``) are valid, and whether one was;
        drawn in batches of ``stages`` (default 2, 4, 8, ... adding up to ``retries``).

        All re-draws are made at once; taking the first valid one is the same as drawing
        until one is valid (on failure the last draw is returned with ``ok = False``).
        """
        n = genes.size
        y_out = np.zeros(n)
        found = np.zeros(n, dtype=bool)
        todo = np.arange(n)
        t = self.tables
        # table positions of the fixed end points, found once (None: use _seg_ok)
        ia = self._layer_index(genes, left)
        ib = None if right is None else self._layer_index(genes + 2, right)
        for R in stages or _stages(self.retries):
            if todo.size == 0:
                break
            gr = np.repeat(genes[todo], R)
            y = self.draw(gr, rng)
            p = self._point(gr, y)
            ip = None if ia is None or (right is not None and ib is None) \
                else self._layer_index(gr + 1, p)
            if ip is not None:  # then the tables and the end points' positions are known
                assert t is not None and ia is not None
                ok = t.valid[t.offset[gr] + np.repeat(ia[todo], R) * t.sizes[gr + 1] + ip]
                if right is not None:
                    assert ib is not None
                    ok &= t.valid[t.offset[gr + 1] + ip * t.sizes[gr + 2]
                                  + np.repeat(ib[todo], R)]
            else:
                ok = self._seg_ok(gr, np.repeat(left[todo], R, 0), p)
                if right is not None:
                    ok &= self._seg_ok(gr + 1, p, np.repeat(right[todo], R, 0))
            ok = ok.reshape(todo.size, R)
            hit = ok.any(1)
            pick = np.where(hit, np.argmax(ok, axis=1), R - 1)
            y_out[todo] = y.reshape(todo.size, R)[np.arange(todo.size), pick]
            found[todo[hit]] = True
            todo = todo[~hit]
        return y_out, found

    def initial_population(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """``n`` chromosomes built point by point as in the paper (see module doc)."""
        d = self.enc.dim
        x = np.zeros((n, d))
        todo = np.arange(n)
        for _ in range(self.restarts + 1):
            prev = np.broadcast_to(self.enc.start, (todo.size, 2)).copy()
            bad = np.zeros(todo.size, dtype=bool)
            for g in range(d):
                y, ok = self._first_valid(np.full(todo.size, g), prev, None, rng)
                bad |= ~ok
                x[todo, g] = y
                prev = self._point(np.full(todo.size, g), y)
            goal = np.broadcast_to(self.enc.goal, (todo.size, 2))
            todo = todo[bad | ~self._seg_ok(np.full(todo.size, d), prev, goal)]
            if todo.size == 0:
                break
        return x

    def mutate(self, x: np.ndarray, rng: np.random.Generator, rate: float) -> np.ndarray:
        """The paper's mutation on each row with probability ``rate`` (see module doc)."""
        n, d = x.shape
        u = rng.random((n,))  # u < rate picks the row; u / rate (uniform) picks the point
        rows = (u < rate).nonzero()[0]
        x = np.array(x, dtype=float)
        if rows.size == 0:
            return x
        # point 0 is the start point: no change
        point = np.minimum((u[rows] * ((d + 1) / rate)).astype(np.int64), d)
        moved = point > 0
        rows, genes = rows[moved], point[moved] - 1
        if rows.size == 0:
            return x
        k = np.arange(rows.size)
        t = self.tables  # set wherever piece_cell is
        cells = None if self.piece_cell is None or t is None else t.gene_cells(x[rows])
        if cells is not None:  # discrete mode: lookups only
            full = np.zeros((rows.size, d + 2), dtype=np.int64)  # S and G: position 0
            full[:, 1:-1] = cells
            y, ok = self._first_valid_cells(genes, full[k, genes], full[k, genes + 2], rng)
        else:
            poly = self.enc.decode(x[rows])
            y, ok = self._first_valid(genes, poly[k, genes], poly[k, genes + 2], rng,
                                      [self.retries])
        x[rows[ok], genes[ok]] = y[ok]
        return x
