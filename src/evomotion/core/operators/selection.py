"""Parent selection on costs (minimised; ``+inf`` marks failed individuals).

Signature: ``fn(cost[pop], n, rng, **params) -> idx[n]``.

Sources: roulette wheel / fitness-proportional selection (Holland 1975; Goldberg 1989);
tournament selection (Goldberg & Deb 1991); linear ranking (Baker 1985).
"""

from __future__ import annotations

from functools import partial

import numpy as np

from evomotion.core.registry import register

SELECTIONS: dict = {}
_reg = partial(register, SELECTIONS)


def _finite_cost(cost: np.ndarray) -> np.ndarray:
    cost = np.asarray(cost, dtype=float)
    finite = np.isfinite(cost)
    if not finite.any():
        return np.zeros_like(cost)
    worst = cost[finite].max()
    return np.where(finite, cost, worst)


@_reg("roulette")
def roulette(cost, n: int, rng: np.random.Generator) -> np.ndarray:
    """Fitness-proportional selection that is safe for any sign and for ties.

    Weights are ``worst - cost + eps * spread`` (so the worst individual keeps a small
    chance, as with the paper's shifted fitness) and failed (``inf``) ones get weight 0.
    Equal costs give a uniform draw. Sampling is stochastic universal sampling free
    (independent draws via ``searchsorted``).
    """
    cost = np.asarray(cost, dtype=float)
    finite = np.isfinite(cost)
    if not finite.any():
        return rng.integers(0, cost.size, n)
    c = _finite_cost(cost)
    spread = c.max() - c.min()
    w = (c.max() - c) + (1e-3 * spread if spread > 0 else 1.0)
    w = np.where(finite, w, 0.0)
    cdf = np.cumsum(w)
    idx = np.searchsorted(cdf, rng.random(n) * cdf[-1], side="right")
    return np.minimum(idx, cost.size - 1)


@_reg("tournament")
def tournament(cost, n: int, rng: np.random.Generator, k: int = 2) -> np.ndarray:
    """Each slot goes to the best of ``k`` individuals drawn with replacement."""
    cost = np.asarray(cost, dtype=float)
    if k < 1:
        raise ValueError(f"tournament size k must be >= 1, got {k}")
    cand = rng.integers(0, cost.size, size=(n, k))
    win = np.argmin(cost[cand], axis=1)
    return cand[np.arange(n), win]


@_reg("rank")
def rank(cost, n: int, rng: np.random.Generator, pressure: float = 1.7) -> np.ndarray:
    """Linear ranking (Baker): best gets ``pressure``, worst ``2 - pressure`` expected copies."""
    if not 1.0 <= pressure <= 2.0:
        raise ValueError(f"rank selection pressure must be in [1, 2], got {pressure}")
    cost = np.asarray(cost, dtype=float)
    m = cost.size
    order = np.argsort(cost, kind="stable")
    ranks = np.empty(m)
    ranks[order] = np.arange(m)[::-1]  # best -> m-1
    w = (2 - pressure) + 2 * (pressure - 1) * ranks / max(m - 1, 1)
    cdf = np.cumsum(w)
    idx = np.searchsorted(cdf, rng.random(n) * cdf[-1], side="right")
    return np.minimum(idx, m - 1)
