"""The update steps of CMA-ES, one function per equation group of the tutorial.

Source: N. Hansen, "The CMA Evolution Strategy: A Tutorial", arXiv:1604.00772, appendix A
(equation numbers below), with the injected-solution clipping of N. Hansen, "Injecting
External Solutions Into CMA-ES", arXiv:1110.4181. Pure functions of the strategy parameters
(:mod:`evomotion.core.cmaes_params`) and arrays of the state; nothing is modified in place.
Steps ``y_i`` are in normalised coordinates and sorted by cost (``y_{i:lambda}``).
"""

from __future__ import annotations

import math

import numpy as np

from evomotion.core.cmaes_params import StrategyParams


def sample(rng: np.random.Generator, lam: int, mean: np.ndarray, sigma: float,
           B: np.ndarray, D: np.ndarray) -> np.ndarray:
    """``x_k = m + sigma B D z_k`` with ``z_k ~ N(0, I)`` (eqs. 38-40)."""
    z = rng.standard_normal((lam, mean.size))
    return mean + sigma * (z * D) @ B.T


def clip_injected(y: np.ndarray, changed: np.ndarray, B: np.ndarray, D: np.ndarray):
    """``(y, C^{-1/2} y, ||C^{-1/2} y||)`` with the rows of candidates not drawn from the
    distribution (``changed``) shortened to Mahalanobis length at most
    ``c_y = sqrt(n) + 2 n / (n + 2)`` (Hansen 2011)."""
    n = y.shape[1]
    z = ((y @ B) / D) @ B.T  # C^{-1/2} y
    znorm = np.linalg.norm(z, axis=1)
    c_y = math.sqrt(n) + 2 * n / (n + 2)
    clip = np.where(changed, np.minimum(1.0, c_y / np.maximum(znorm, 1e-300)), 1.0)
    return y * clip[:, None], z * clip[:, None], znorm * clip


def update_mean(p: StrategyParams, mean: np.ndarray, sigma: float, y: np.ndarray):
    """``<y>_w = sum_i w_i y_{i:lambda}`` (eq. 41) and ``m + c_m sigma <y>_w`` (eq. 42);
    returns ``(mean, <y>_w)``."""
    y_w = p.weights[: p.mu] @ y[: p.mu]
    return mean + p.c_m * sigma * y_w, y_w


def update_evolution_paths(p: StrategyParams, p_sigma: np.ndarray, p_c: np.ndarray,
                           z: np.ndarray, y_w: np.ndarray, generation: int):
    """The conjugate path ``p_sigma`` (eq. 43, ``C^{-1/2} <y>_w`` as ``sum w_i z_i``), the
    stall indicator ``h_sigma`` (after eq. 45; ``generation`` is the tutorial's ``g + 1``)
    and the path ``p_c`` (eq. 45); returns ``(p_sigma, p_c, h_sigma)``."""
    n, w = p_sigma.size, p.weights
    p_sigma = (1 - p.c_sigma) * p_sigma + math.sqrt(
        p.c_sigma * (2 - p.c_sigma) * p.mu_eff) * (w[: p.mu] @ z[: p.mu])
    ps_norm = float(np.linalg.norm(p_sigma))
    h_sigma = (ps_norm / math.sqrt(1 - (1 - p.c_sigma) ** (2 * generation))
               < (1.4 + 2 / (n + 1)) * p.chi_n)
    p_c = (1 - p.c_c) * p_c + h_sigma * math.sqrt(p.c_c * (2 - p.c_c) * p.mu_eff) * y_w
    return p_sigma, p_c, h_sigma


def update_covariance(p: StrategyParams, C: np.ndarray, p_c: np.ndarray, h_sigma: bool,
                      y: np.ndarray, znorm: np.ndarray, changed: np.ndarray) -> np.ndarray:
    """Rank-one plus rank-mu update with active weights (eq. 47).

    The negative weights are rescaled to ``w_i n / ||C^{-1/2} y_i||^2`` (eq. 46); injected
    candidates (``changed``) get none: the active update assumes samples of the distribution.
    """
    w, n = p.weights, C.shape[0]
    w_circ = np.where(w >= 0, w, w * n / np.maximum(znorm**2, 1e-300))
    w_circ[(w < 0) & changed] = 0.0
    delta_h = (1 - h_sigma) * p.c_c * (2 - p.c_c)
    return ((1 + p.c_1 * delta_h - p.c_1 - p.c_mu * w.sum()) * C
            + p.c_1 * np.outer(p_c, p_c) + p.c_mu * (y.T * w_circ) @ y)


def update_step_size(p: StrategyParams, sigma: float, p_sigma: np.ndarray,
                     costs_sorted: np.ndarray) -> float:
    """Cumulative step-size adaptation ``sigma exp(c_sigma / d_sigma (||p_sigma|| / E||N(0,
    I)|| - 1))`` (eq. 44; the exponent capped at 1), enlarged on flat fitness (the best and
    the ``ceil(0.7 lambda)``-th cost equal; tutorial, appendix B.3 "flat fitness")."""
    lam = costs_sorted.size
    ps_norm = float(np.linalg.norm(p_sigma))
    sigma = sigma * math.exp(min(1.0, p.c_sigma / p.d_sigma * (ps_norm / p.chi_n - 1)))
    if costs_sorted[0] == costs_sorted[min(lam - 1, int(math.ceil(0.7 * lam)) - 1)]:
        sigma *= math.exp(0.2 + p.c_sigma / p.d_sigma)
    return sigma


def update_eigensystem(C: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(C, B, D)``: ``C`` symmetrised, ``C = B D^2 B^T`` (appendix B.2)."""
    C = 0.5 * (C + C.T)
    evals, B = np.linalg.eigh(C)
    return C, B, np.sqrt(np.maximum(evals, 1e-300))
