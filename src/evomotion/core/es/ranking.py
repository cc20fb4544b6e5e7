"""Rank-based fitness shaping of costs (minimised), with ties handled deterministically.

- :func:`centered_ranks`: Salimans et al. 2017, "Evolution Strategies as a Scalable
  Alternative to Reinforcement Learning" (arXiv:1703.03864), their fitness shaping:
  ranks scaled to ``[-0.5, 0.5]``; used by OpenAI-ES and PGPE (Toklu et al. 2020).
- :func:`nes_utilities`: Wierstra et al. 2014, "Natural Evolution Strategies" (JMLR 15),
  their fitness shaping, also the utilities of the SNES paper (Schaul et al. 2011):
  ``u_k = max(0, ln(λ/2 + 1) - ln k) / Σ_j max(0, ln(λ/2 + 1) - ln j) - 1/λ`` for rank
  ``k = 1..λ`` (1 = best).

Both return a *utility*: larger for a lower cost, so ascending the utility-weighted
gradient lowers the cost. Equal costs get equal utilities: the mean of the values of the
rank positions they share (so the result never depends on the order of the rows, and the
utilities still sum to what the untied ones sum to). ``nan`` costs count as ``+inf``.
"""

from __future__ import annotations

import numpy as np


def _tie_averaged(by_rank: np.ndarray, cost: np.ndarray) -> np.ndarray:
    """``by_rank[r]`` is the value of rank position ``r`` (0 = lowest cost); every cost gets
    the mean of the values of the positions its ties occupy."""
    c = np.where(np.isnan(cost), np.inf, np.asarray(cost, dtype=float))
    ordered = np.sort(c)
    lo = np.searchsorted(ordered, c, side="left")
    hi = np.searchsorted(ordered, c, side="right")
    csum = np.concatenate(([0.0], np.cumsum(by_rank)))
    out: np.ndarray = np.where(hi - lo == 1, by_rank[np.minimum(lo, len(c) - 1)],
                               (csum[hi] - csum[lo]) / (hi - lo))  # untied: exact values
    return out


def centered_ranks(cost: np.ndarray) -> np.ndarray:
    """Utilities in ``[-0.5, 0.5]`` summing to zero: ``0.5`` for the lowest cost, ``-0.5``
    for the highest (Salimans et al. 2017, fitness shaping); zeros for fewer than 2 costs."""
    n = len(cost)
    if n < 2:
        return np.zeros(n)
    return _tie_averaged(0.5 - np.arange(n) / (n - 1), cost)


def nes_utilities(cost: np.ndarray) -> np.ndarray:
    """NES utilities (Wierstra et al. 2014, sec. 3.1; Schaul et al. 2011): they sum to zero,
    the worse half gets ``-1/λ``."""
    n = len(cost)
    k = np.arange(1, n + 1)
    raw = np.maximum(0.0, np.log(n / 2 + 1) - np.log(k))
    return _tie_averaged(raw / raw.sum() - 1.0 / n, cost)
