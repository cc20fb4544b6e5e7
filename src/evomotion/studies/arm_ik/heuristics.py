"""Wrist heuristics of paper 001 (section 3.1): board cells, reachability and wrist candidates.

The board is cut into square cells of side ``cell`` (default: diagonal / 150). A cell is
*reachable* when its centre connects to the start's cell through 4-neighbour steps whose
centre-to-centre segment crosses no obstacle (connected components of that grid graph). A
reachable cell is a *wrist candidate* when the start lies within the arm's [min, max] reach of
its centre and the targets can be matched to distinct fingers, each target within its finger's
[min, max] reach (reaches from :meth:`Chain.reach`, widened by half a cell diagonal so thin
annuli are not missed). The arm phase minimises the wrist's distance to the nearest candidate
cell centre (a Euclidean distance transform of the candidate mask).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from scipy import ndimage, sparse
from scipy.sparse import csgraph

from evomotion.studies.arm_ik.geometry import segments_intersect
from evomotion.studies.arm_ik.scenario import Scenario


@dataclass(frozen=True)
class WristMap:
    """Cell grid with ``reachable``/``candidate`` masks ``[ny, nx]`` and ``dist`` (board units)."""

    cell: float
    width: float
    height: float
    reachable: np.ndarray
    candidate: np.ndarray
    dist: np.ndarray  # distance from each cell centre to the nearest candidate centre
    reach_gap: np.ndarray  # per cell: how far the centre is outside the reach intervals

    def centres(self) -> np.ndarray:
        ny, nx = self.reachable.shape
        xs = (np.arange(nx) + 0.5) * self.cell
        ys = (np.arange(ny) + 0.5) * self.cell
        return np.stack(np.meshgrid(xs, ys), axis=-1)  # (ny, nx, 2)

    def wrist_distance(self, pts: np.ndarray) -> np.ndarray:
        """Distance of points ``[..., 2]`` to the nearest candidate cell (plus any distance off
        the board). Without any candidate cell, the reach-interval gap of the nearest cell."""
        ny, nx = self.reachable.shape
        ix = np.clip((pts[..., 0] / self.cell).astype(int), 0, nx - 1)
        iy = np.clip((pts[..., 1] / self.cell).astype(int), 0, ny - 1)
        off = np.hypot(np.maximum(0, np.maximum(-pts[..., 0], pts[..., 0] - self.width)),
                       np.maximum(0, np.maximum(-pts[..., 1], pts[..., 1] - self.height)))
        table = self.dist if self.candidate.any() else self.reach_gap
        return table[iy, ix] + off


def _blocked(a: np.ndarray, b: np.ndarray, obstacles: np.ndarray) -> np.ndarray:
    """Whether segment ``a[k] -> b[k]`` meets any obstacle edge (chunked over k)."""
    out = np.zeros(a.shape[0], dtype=bool)
    if obstacles.shape[0] == 0:
        return out
    seg = np.stack([a, b], axis=1)
    step = max(1, 200_000 // obstacles.shape[0])
    for i in range(0, seg.shape[0], step):
        hit = segments_intersect(seg[i:i + step, None], obstacles[None])
        out[i:i + step] = hit.any(axis=1)
    return out


def reachable_cells(scn: Scenario, cell: float) -> np.ndarray:
    """``bool[ny, nx]``: cells connected to the start's cell around the obstacles."""
    nx = max(1, int(np.ceil(scn.width / cell)))
    ny = max(1, int(np.ceil(scn.height / cell)))
    ids = np.arange(nx * ny).reshape(ny, nx)
    cx = (np.arange(nx) + 0.5) * cell
    cy = (np.arange(ny) + 0.5) * cell
    centre = np.stack(np.meshgrid(cx, cy), axis=-1).reshape(-1, 2)
    obst = scn.obstacle_segments()
    src = np.concatenate([ids[:, :-1].ravel(), ids[:-1, :].ravel()])
    dst = np.concatenate([ids[:, 1:].ravel(), ids[1:, :].ravel()])
    ok = ~_blocked(centre[src], centre[dst], obst)
    g = sparse.coo_matrix((np.ones(ok.sum()), (src[ok], dst[ok])), shape=(nx * ny, nx * ny))
    _, labels = csgraph.connected_components(g, directed=False)
    sx = min(nx - 1, int(scn.start[0] / cell))
    sy = min(ny - 1, int(scn.start[1] / cell))
    return (labels == labels[ids[sy, sx]]).reshape(ny, nx)


def _gap(d: np.ndarray, lo: float, hi: float) -> np.ndarray:
    return np.maximum(0.0, np.maximum(lo - d, d - hi))


def build_wrist_map(scn: Scenario, cell: float = 0.0) -> WristMap:
    """Paper 001's heuristic map; ``cell <= 0`` picks diagonal / 150."""
    cell = cell if cell > 0 else scn.diagonal / 150.0
    reach = reachable_cells(scn, cell)
    ny, nx = reach.shape
    xs, ys = (np.arange(nx) + 0.5) * cell, (np.arange(ny) + 0.5) * cell
    c = np.stack(np.meshgrid(xs, ys), axis=-1)  # (ny, nx, 2)
    slack = cell * np.sqrt(0.5)
    lo, hi = scn.arm.reach()
    gap = _gap(np.linalg.norm(c - scn.start, axis=-1), lo - slack, hi + slack)
    d_t = np.linalg.norm(c[:, :, None, :] - scn.targets, axis=-1)  # (ny, nx, T)
    f_gap = np.stack([_gap(d_t, f.reach()[0] - slack, f.reach()[1] + slack)
                      for f in scn.fingers], axis=2)  # (ny, nx, F, T)
    n = scn.n_targets
    best = np.full((ny, nx), np.inf)
    perms = np.array(list(itertools.permutations(range(n)))) if n <= 7 else None
    if perms is not None:
        tot = f_gap[:, :, np.arange(n), perms].sum(axis=-1)  # (ny, nx, P)
        best = tot.min(axis=-1)
    else:  # greedy bound for very many fingers
        best = f_gap.min(axis=2).sum(axis=-1)
    reach_gap = gap + best
    candidate = reach & (reach_gap <= 0)
    if candidate.any():
        dist = ndimage.distance_transform_edt(~candidate) * cell
    else:
        dist = np.full((ny, nx), np.inf)
    return WristMap(cell, scn.width, scn.height, reach, candidate, dist, reach_gap)
