"""Quality-diversity archives: a grid and a centroidal Voronoi (CVT) tessellation.

Sources: J.-B. Mouret and J. Clune, "Illuminating search spaces by mapping elites",
arXiv:1504.04909 (2015): one elite per cell of a grid over the behaviour descriptors;
V. Vassiliades, K. Chatzilygeroudis and J.-B. Mouret, "Using Centroidal Voronoi Tessellations
to Scale Up the Multidimensional Archive of Phenotypic Elites Algorithm", IEEE TEVC 22(4),
2018: the cells are the Voronoi regions of ``cells`` centroids, found by k-means (Lloyd's
iterations) on uniform samples of the descriptor box; M. C. Fontaine and S. Nikolaidis,
"Covariance Matrix Adaptation MAP-Annealing", GECCO 2023, eq. 2: the acceptance threshold
``t_e <- (1 - alpha) t_e + alpha f`` of CMA-MAE (``alpha = 1``: the elitist archive of
MAP-Elites and CMA-ME).

An :class:`ArchiveSpec` holds the settings; everything that changes is an
:class:`ArchiveState` of arrays, replaced by :func:`add` and never mutated, so an archive
checkpoints like any optimizer state (npz + JSON). The objective is *maximised* here
(``objective = -cost``).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from evomotion.core.state import replaced

#: status of a candidate after :func:`add`
NOT_ADDED, IMPROVED, NEW_CELL = 0, 1, 2


@dataclass
class ArchiveState:
    """The elites: per cell its genome, objective and measures; ``threshold`` is the CMA-MAE
    acceptance threshold (the elite's objective when ``alpha = 1``); ``centroids`` the CVT
    centroids (``[0, m]`` for a grid)."""

    solutions: np.ndarray  # [cells, d]
    objective: np.ndarray  # [cells], -inf where empty
    measures: np.ndarray  # [cells, m]
    occupied: np.ndarray  # bool[cells]
    threshold: np.ndarray  # [cells]
    centroids: np.ndarray  # [cells, m] (CVT) or [0, m] (grid)


@dataclass(frozen=True)
class ArchiveSpec:
    """``kind`` "grid" (``bins`` per measure) or "cvt" (``cells`` centroids from
    ``samples`` uniform samples and ``iterations`` Lloyd steps) over the box
    ``lower``..``upper`` of the measures."""

    kind: str
    lower: np.ndarray
    upper: np.ndarray
    bins: tuple[int, ...] = ()
    cells_cvt: int = 0
    samples: int = 100_000
    iterations: int = 20

    @property
    def cells(self) -> int:
        return int(np.prod(self.bins)) if self.kind == "grid" else int(self.cells_cvt)

    @property
    def measure_dim(self) -> int:
        return int(np.asarray(self.lower).size)

    def init(self, rng: np.random.Generator, solution_dim: int,
             threshold_min: float = -np.inf) -> ArchiveState:
        """An empty archive (the CVT centroids drawn from ``rng``)."""
        c, m = self.cells, self.measure_dim
        cent = cvt_centroids(rng, self.lower, self.upper, c, self.samples, self.iterations) \
            if self.kind == "cvt" else np.zeros((0, m))
        return ArchiveState(np.zeros((c, solution_dim)), np.full(c, -np.inf),
                            np.full((c, m), np.nan), np.zeros(c, bool),
                            np.full(c, float(threshold_min)), cent)

    def index(self, state: ArchiveState, measures: np.ndarray) -> np.ndarray:
        """The cell of each row of ``measures[n, m]`` (outside the box: the nearest cell)."""
        meas = np.asarray(measures, dtype=float)
        if self.kind == "grid":
            lo, hi = np.asarray(self.lower), np.asarray(self.upper)
            b = np.asarray(self.bins)
            k = np.floor((meas - lo) / (hi - lo) * b).astype(np.int64)
            k = np.clip(k, 0, b - 1)
            return np.ravel_multi_index(tuple(k.T), self.bins)
        return _tree(state.centroids).query(meas)[1].astype(np.int64)

    def cell_centres(self, state: ArchiveState) -> np.ndarray:
        """Centre of every cell in measure space ``[cells, m]``."""
        if self.kind == "cvt":
            return state.centroids
        lo, hi = np.asarray(self.lower), np.asarray(self.upper)
        axes = [lo[i] + (np.arange(n) + 0.5) * (hi[i] - lo[i]) / n
                for i, n in enumerate(self.bins)]
        return np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=1)


_TREES: dict[str, cKDTree] = {}


def _tree(centroids: np.ndarray) -> cKDTree:
    """A k-d tree over the centroids, cached by their bytes (a restored checkpoint finds
    the same tree)."""
    key = hashlib.blake2b(np.ascontiguousarray(centroids).tobytes(), digest_size=16).hexdigest()
    tree = _TREES.get(key)
    if tree is None:
        if len(_TREES) > 8:
            _TREES.clear()
        tree = _TREES[key] = cKDTree(centroids)
    return tree


def cvt_centroids(rng: np.random.Generator, lower: np.ndarray, upper: np.ndarray, cells: int,
                  samples: int, iterations: int) -> np.ndarray:
    """``cells`` centroids of a CVT of the box: Lloyd's k-means on ``samples`` uniform points
    (Vassiliades et al. 2018, Alg. 1), started from ``cells`` of the samples; an empty
    region keeps its previous centroid."""
    lo, hi = np.asarray(lower, float), np.asarray(upper, float)
    x = rng.uniform(lo, hi, size=(max(int(samples), cells), lo.size))
    c = x[rng.choice(len(x), size=cells, replace=False)].copy()
    for _ in range(int(iterations)):
        label = cKDTree(c).query(x)[1]
        count = np.bincount(label, minlength=cells)
        sums = np.stack([np.bincount(label, weights=x[:, j], minlength=cells)
                         for j in range(lo.size)], axis=1)
        filled = count > 0
        c[filled] = sums[filled] / count[filled, None]
    return c


def add(spec: ArchiveSpec, state: ArchiveState, x: np.ndarray, objective: np.ndarray,
        measures: np.ndarray, alpha: float = 1.0
        ) -> tuple[ArchiveState, np.ndarray, np.ndarray]:
    """Insert a batch; returns ``(new state, status[n], value[n])``.

    A candidate is accepted when its objective exceeds its cell's threshold (``-inf`` for an
    empty cell of an elitist archive, the elite's objective otherwise). Of several accepted
    candidates for one cell the best becomes the elite. ``status``: :data:`NEW_CELL`,
    :data:`IMPROVED` or :data:`NOT_ADDED`; ``value`` = objective minus the cell's threshold
    before the batch (for a new cell of an elitist archive: the objective), what the
    improvement ranking of CMA-ME orders by. With ``alpha < 1`` (CMA-MAE) the threshold then
    moves towards each accepted objective in turn, in ascending order (eq. 2). Rows with a
    non-finite objective or measure are never added."""
    obj = np.asarray(objective, dtype=float)
    n = obj.size
    valid = np.isfinite(obj) & np.isfinite(measures).all(axis=1)
    status = np.zeros(n, np.int64)
    value = np.full(n, -np.inf)
    if not valid.any():
        return state, status, value
    rows = np.flatnonzero(valid)
    cell = spec.index(state, measures[rows])
    t_old = state.threshold[cell]
    was = state.occupied[cell]
    ok = obj[rows] > t_old
    value[rows] = np.where(was | np.isfinite(t_old), obj[rows] - t_old, obj[rows])
    status[rows[ok]] = np.where(was[ok], IMPROVED, NEW_CELL)
    if not ok.any():
        return state, status, value
    acc, acc_cell = rows[ok], cell[ok]
    order = np.lexsort((obj[acc], acc_cell))  # by cell, then ascending objective
    acc, acc_cell = acc[order], acc_cell[order]
    last = np.r_[acc_cell[1:] != acc_cell[:-1], True]  # the best of each cell
    win, win_cell = acc[last], acc_cell[last]
    sol, ob, me, occ = (state.solutions.copy(), state.objective.copy(),
                        state.measures.copy(), state.occupied.copy())
    sol[win_cell], ob[win_cell], me[win_cell], occ[win_cell] = x[win], obj[win], \
        measures[win], True
    th = state.threshold.copy()
    if alpha >= 1.0:
        th[win_cell] = obj[win]
    else:
        first = np.r_[True, acc_cell[1:] != acc_cell[:-1]]
        rank = np.arange(acc.size) - np.maximum.accumulate(np.where(first, np.arange(acc.size),
                                                                    0))
        for r in range(int(rank.max()) + 1):  # sequential within a cell, vectorised across
            k = rank == r
            th[acc_cell[k]] = (1.0 - alpha) * th[acc_cell[k]] + alpha * obj[acc[k]]
    return replaced(state, solutions=sol, objective=ob, measures=me, occupied=occ,
                    threshold=th), status, value


def stats(state: ArchiveState, offset: float = 0.0) -> dict[str, float]:
    """``archive_size``, ``coverage`` (filled / cells), ``qd_score`` (sum over filled cells
    of objective - ``offset``; Pugh et al. 2016) and ``qd_best`` (largest objective)."""
    occ = state.occupied
    size = int(occ.sum())
    obj = state.objective[occ]
    return {"archive_size": size, "coverage": size / max(occ.size, 1),
            "qd_score": float((obj - offset).sum()) if size else 0.0,
            "qd_best": float(obj.max()) if size else float("nan")}
