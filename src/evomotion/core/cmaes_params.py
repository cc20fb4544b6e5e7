"""Default strategy parameters of CMA-ES for dimension ``n`` and population ``lambda``.

All formulas from N. Hansen, "The CMA Evolution Strategy: A Tutorial", arXiv:1604.00772,
Table 1 (lambda, eq. 48; the weights incl. the negative "active" weights, eqs. 49-53; c_m,
c_sigma, d_sigma, c_c, c_1, c_mu) and the lazy eigendecomposition interval of its appendix B.2.
``c_mu`` uses ``mu_eff - 2 + 1/mu_eff`` (the tutorial's 2016 form, without the later ``+1/4``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np


@dataclass(frozen=True)
class StrategyParams:
    lam: int
    mu: int
    weights: np.ndarray  # [lam]; first mu positive (sum 1), the rest negative (do not modify)
    mu_eff: float
    c_sigma: float
    d_sigma: float
    c_c: float
    c_1: float
    c_mu: float
    c_m: float
    chi_n: float  # E||N(0, I)||
    eigen_every: float  # generations between eigendecompositions (lazy update gap)


def default_lambda(n: int) -> int:
    """Default population size ``4 + floor(3 ln n)`` (Table 1, eq. 48)."""
    return 4 + int(3 * math.log(n))


@lru_cache(maxsize=64)
def strategy_params(n: int, lam: int) -> StrategyParams:
    """Tutorial defaults (Hansen 2016, Table 1) for ``n`` dimensions and ``lam`` offspring.

    A pure function of ``(n, lam)``, memoised (restarts change ``lam``)."""
    if lam < 2:
        raise ValueError(f"CMA-ES needs lambda >= 2, got {lam}")
    mu = lam // 2
    w_prime = math.log((lam + 1) / 2) - np.log(np.arange(1, lam + 1))  # eq. 49
    pos, neg = w_prime[:mu], w_prime[mu:]
    mu_eff = float(pos.sum() ** 2 / (pos**2).sum())
    mu_eff_neg = float(neg.sum() ** 2 / (neg**2).sum()) if neg.size and neg.sum() != 0 else 0.0
    alpha_cov = 2.0
    c_c = (4 + mu_eff / n) / (n + 4 + 2 * mu_eff / n)
    c_sigma = (mu_eff + 2) / (n + mu_eff + 5)
    c_1 = alpha_cov / ((n + 1.3) ** 2 + mu_eff)
    c_mu = min(1 - c_1, alpha_cov * (mu_eff - 2 + 1 / mu_eff)
               / ((n + 2) ** 2 + alpha_cov * mu_eff / 2))
    d_sigma = 1 + 2 * max(0.0, math.sqrt((mu_eff - 1) / (n + 1)) - 1) + c_sigma
    weights = np.empty(lam)
    weights[:mu] = pos / pos.sum()
    if neg.size and neg.sum() != 0:  # active weights, eqs. 50-53
        alpha_mu_neg = 1 + c_1 / c_mu if c_mu > 0 else math.inf
        alpha_mueff_neg = 1 + 2 * mu_eff_neg / (mu_eff + 2)
        alpha_posdef_neg = (1 - c_1 - c_mu) / (n * c_mu) if c_mu > 0 else math.inf
        scale = min(alpha_mu_neg, alpha_mueff_neg, alpha_posdef_neg)
        weights[mu:] = scale * neg / np.abs(neg).sum()
    else:
        weights[mu:] = 0.0
    weights.setflags(write=False)  # shared by every caller of the memoised result
    chi_n = math.sqrt(n) * (1 - 1 / (4 * n) + 1 / (21 * n * n))
    eigen_every = 1 / (10 * n * (c_1 + c_mu))
    return StrategyParams(lam, mu, weights, mu_eff, c_sigma, d_sigma, c_c, c_1, c_mu, 1.0,
                          chi_n, eigen_every)
