"""Paper 001's evolutionary operators and one generation step (Januszkiewicz & Kowalski 2011,
sections 3.2-3.3; infeasible-individual retention after IDEA, Singh, Isaacs & Ray 2008).

- Crossover: a pair of parents gives a pair of children. Each active angle is inherited (with a
  uniform swap) or, with probability ``blend_prob``, blended by the engine's ``beta_blend``:
  ``(a1 + a2 + beta (a1 - a2)) / 2`` and ``(a1 + a2 + beta (a2 - a1)) / 2``, beta ~ U(0, 1).
  The *mode* decides which genes are active: ``arm`` (fingers inherited), ``fingers`` (arm
  inherited) or ``whole``. Full-circle angles are blended along the shorter arc when
  ``circular`` (350 and 10 degrees blend towards 0, not 180).
- Mutation: one active angle per child is perturbed by ``+-m``, ``m`` log-uniform in
  [min_deg, max_deg] (so the step sizes cover coarse moves and the 1e-3 fine tuning alike);
  full-circle angles wrap around, limited ones are clipped to [min, max].
- Survival: a binary tournament over parents and children, every individual in exactly one
  pairing, so the best always survives and nobody is copied twice. Feasible beats infeasible;
  two infeasible compare by intersections then objective; two feasible by objective. Then
  IDEA: if fewer than ``infeasible_fraction * N`` survivors are infeasible, the worst feasible
  survivors give way to the best (by objective) infeasible losers.
"""

from __future__ import annotations

import numpy as np

from evomotion.core.operators.crossover import CROSSOVERS
from evomotion.core.operators.selection import SELECTIONS
from evomotion.core.registry import lookup
from evomotion.studies.arm_ik.kinematics import Layout

MODES = ("arm", "fingers", "whole")


def active_genes(layout: Layout, mode: str) -> np.ndarray:
    """Boolean mask of the genes a phase evolves."""
    m = np.zeros(layout.dim, dtype=bool)
    if mode in ("arm", "whole"):
        m[layout.arm] = True
    if mode in ("fingers", "whole"):
        m[layout.fingers] = True
    return m


def wrap(x: np.ndarray, layout: Layout) -> np.ndarray:
    """Wrap full-circle genes into [min, min + 360), clip the others into their limits."""
    circ = layout.full_circle
    y = np.clip(x, layout.lower, layout.upper)
    w = layout.lower + np.mod(x - layout.lower, 360.0)
    return np.where(circ, w, y)


def crossover(a: np.ndarray, b: np.ndarray, layout: Layout, mode: str, rng: np.random.Generator,
              blend_prob: float = 0.5, circular: bool = True) -> np.ndarray:
    """Children ``(2n, d)`` of parent pairs ``a[n, d]``, ``b[n, d]`` (paper's beta crossover)."""
    act = active_genes(layout, mode)
    circ = layout.full_circle if circular else np.zeros(layout.dim, dtype=bool)
    b_near = np.where(circ, a + np.mod(b - a + 180.0, 360.0) - 180.0, b)
    blended = lookup(CROSSOVERS, "crossover", "beta_blend")(a, b_near, rng)  # (2, n, d)
    swap = (rng.random(a.shape) < 0.5) & act
    blend = (rng.random(a.shape) < blend_prob) & act
    c1 = np.where(blend, blended[0], np.where(swap, b, a))
    c2 = np.where(blend, blended[1], np.where(swap, a, b))
    return wrap(np.concatenate([c1, c2]), layout)


def mutate(x: np.ndarray, layout: Layout, mode: str, rng: np.random.Generator, rate: float,
           min_deg: float, max_deg: float) -> np.ndarray:
    """Perturb one active gene of each row with probability ``rate`` (log-uniform step)."""
    n = x.shape[0]
    cols = np.flatnonzero(active_genes(layout, mode))
    rows = np.flatnonzero(rng.random(n) < rate)
    j = cols[rng.integers(0, cols.size, rows.size)]
    mag = np.exp(rng.uniform(np.log(min_deg), np.log(max_deg), rows.size))
    if layout.with_keys:
        mag = np.where(np.isin(j, np.arange(layout.dim)[layout.keys]), mag / 360.0, mag)
    y = x.copy()
    y[rows, j] += mag * rng.choice([-1.0, 1.0], rows.size)
    return wrap(y, layout)


def rank_order(hits: np.ndarray, objective: np.ndarray) -> np.ndarray:
    """Rank (0 = best): fewer intersections first (0 = feasible), then lower objective."""
    order = np.lexsort((objective, hits))
    r = np.empty(hits.size, dtype=int)
    r[order] = np.arange(hits.size)
    return r


def parents(rank: np.ndarray, n_pairs: int, rng: np.random.Generator,
            k: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Parent pairs by the engine's tournament on ranks."""
    sel = lookup(SELECTIONS, "selection", "tournament")
    idx = sel(rank.astype(float), 2 * n_pairs, rng, k=k)
    return idx[:n_pairs], idx[n_pairs:]


def survivors(hits: np.ndarray, objective: np.ndarray, n: int, rng: np.random.Generator,
              infeasible_fraction: float, pairwise: bool = True) -> np.ndarray:
    """Indices of ``n`` survivors out of the pool ``2n`` = parents + children.

    ``pairwise=False`` is the literal reading of the paper: ``n`` binary tournaments drawn with
    replacement from the pool (copies possible, the best may be lost; no IDEA step).
    """
    rank = rank_order(hits, objective)
    if not pairwise:
        return lookup(SELECTIONS, "selection", "tournament")(rank.astype(float), n, rng, k=2)
    perm = rng.permutation(hits.size).reshape(2, n)
    win = np.where(rank[perm[0]] < rank[perm[1]], perm[0], perm[1])
    lose = np.where(rank[perm[0]] < rank[perm[1]], perm[1], perm[0])
    want = int(round(infeasible_fraction * n)) - int(np.count_nonzero(hits[win] > 0))
    if want > 0:
        inf_lose = lose[hits[lose] > 0]
        inf_lose = inf_lose[np.argsort(objective[inf_lose], kind="stable")]
        feas_win = win[hits[win] == 0]
        feas_win = feas_win[np.argsort(-objective[feas_win], kind="stable")]
        m = min(want, inf_lose.size, max(0, feas_win.size - 1))  # never drop the best
        if m:
            keep = np.setdiff1d(win, feas_win[:m])
            win = np.concatenate([keep, inf_lose[:m]])
    return win
