"""Restarts of CMA-ES: IPOP and BIPOP, and the fresh distribution each run starts from.

Sources: A. Auger & N. Hansen, "A Restart CMA Evolution Strategy With Increasing Population
Size", CEC 2005 (IPOP: each restart multiplies lambda by ``inc_popsize``); N. Hansen,
"Benchmarking a BI-Population CMA-ES on the BBOB-2009 Function Testbed", GECCO 2009 (BIPOP:
after the first large restart, a run with a small population ``lambda_0 (lambda_large / (2
lambda_0))^(u^2)`` and step size ``sigma_0 10^(-2u)``, ``u ~ U(0, 1)``, whenever the small
regime has spent fewer evaluations than the large one). Pure functions of the frozen config,
the mask of fixed genes and the state.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from evomotion.core.cmaes_params import default_lambda

if TYPE_CHECKING:
    from evomotion.core.cmaes import CMAESConfig, CMAESState


def initial_lambda(cfg: CMAESConfig, n: int) -> int:
    """``lambda_0``: ``cfg.pop_size``, or the tutorial's default for ``n`` dimensions."""
    return cfg.pop_size or default_lambda(n)


def fresh_distribution(cfg: CMAESConfig, fixed: np.ndarray, rng: np.random.Generator,
                       lam: int, sigma: float) -> dict[str, Any]:
    """State fields of a (re)started run: mean ``x0`` (uniform in the normalised box, or its
    centre; fixed genes 0), ``C = I``, zero paths, empty histories."""
    n = fixed.size
    mean = rng.uniform(0, 1, n) if cfg.x0 == "uniform" else np.full(n, 0.5)
    mean[fixed] = 0.0
    eye = np.eye(n)
    return dict(mean=mean, sigma=float(sigma), C=eye.copy(), B=eye.copy(), D=np.ones(n),
                p_sigma=np.zeros(n), p_c=np.zeros(n), lam=int(lam),
                best_hist=np.zeros(0), median_hist=np.zeros(0), restart_generation=0,
                eigen_generation=0, restart_best=math.inf, since_improvement=0,
                restart_jumps=0)


def restart(cfg: CMAESConfig, fixed: np.ndarray, s: CMAESState, reason: str,
            rng: np.random.Generator) -> CMAESState:
    """The state after the run stopped for ``reason``: restarted (IPOP/BIPOP), or marked
    ``done`` when no restart is left. The last population stays for statistics until the
    next ``ask``."""
    log = f"{s.stop_log};{reason}@{s.evaluations}" if s.stop_log else f"{reason}@{s.evaluations}"
    spent = s.evaluations - s.restart_evals0
    evals_large = s.evals_large + (spent if s.regime == "large" else 0)
    evals_small = s.evals_small + (spent if s.regime == "small" else 0)
    if cfg.restarts == "none" or s.restarts >= cfg.max_restarts:
        # no restart left: keep the distribution (only tolx may leave it degenerate)
        return replace(s, stop_reason=reason, stop_log=log, done=True,
                       evals_large=evals_large, evals_small=evals_small,
                       restart_evals0=s.evaluations)
    lam0 = initial_lambda(cfg, fixed.size)
    regime, large = "large", s.large_restarts
    sigma = cfg.sigma0
    if cfg.restarts == "ipop":
        lam = int(round(lam0 * cfg.inc_popsize ** (s.restarts + 1)))
    elif evals_small < evals_large and large > 0:  # BIPOP small regime
        regime = "small"
        u = rng.uniform()
        lam_large = lam0 * cfg.inc_popsize**large
        lam = max(2, int(lam0 * (0.5 * lam_large / lam0) ** (u * u)))
        sigma = cfg.sigma0 * 10 ** (-2 * u)
    else:  # BIPOP large regime
        large += 1
        lam = int(round(lam0 * cfg.inc_popsize**large))
    return replace(s, **fresh_distribution(cfg, fixed, rng, lam, sigma),
                   restarts=s.restarts + 1, stop_reason=reason, stop_log=log, regime=regime,
                   large_restarts=large, evals_large=evals_large, evals_small=evals_small,
                   restart_evals0=s.evaluations)
