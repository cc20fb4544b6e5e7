"""The ``tell`` step of :class:`evomotion.core.cmaes.CMAES`: update, termination and restarts.

Update equations: N. Hansen, "The CMA Evolution Strategy: A Tutorial", arXiv:1604.00772
(Fig. 6), with injected-solution clipping from Hansen, arXiv:1110.4181, the termination
criteria of the tutorial's appendix B.3, and IPOP (Auger & Hansen 2005) / BIPOP (Hansen 2009)
restarts. See :mod:`evomotion.core.cmaes` for how the seed's Tent and Lévy options enter.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from evomotion.core.cmaes import CMAES, CMAESState

MAX_HISTORY = 20000
CONDITION_LIMIT = 1e14


def cmaes_update(opt: CMAES, s: CMAESState, genomes: np.ndarray, cost: np.ndarray,
                 rng: np.random.Generator) -> CMAESState:
    """One generation's update; returns the new state (restarted if a stop criterion fired)."""
    n, p = opt.n, opt.params(s.lam)
    if genomes.shape[0] != s.lam:
        raise ValueError(f"cmaes: tell got {genomes.shape[0]} genomes, asked {s.lam}")
    s = replace(s, cost=cost.copy(), evaluations=s.evaluations + s.lam,
                total_generations=s.total_generations + 1)
    order = np.argsort(cost, kind="stable")
    if cost[order[0]] < s.best_cost:
        s.best_cost, s.best_x = float(cost[order[0]]), genomes[order[0]].copy()
    if cost[order[0]] < s.restart_best:
        s.restart_best, s.since_improvement = float(cost[order[0]]), 0
    else:
        s.since_improvement += 1

    changed = s.modified | np.any(genomes != s.pop, axis=1)
    y = (opt.to_unit(genomes[order]) - s.mean) / s.sigma
    y[:, opt.fixed] = 0.0
    z = ((y @ s.B) / s.D) @ s.B.T  # C^{-1/2} y
    znorm = np.linalg.norm(z, axis=1)
    c_y = math.sqrt(n) + 2 * n / (n + 2)
    clip = np.where(changed[order], np.minimum(1.0, c_y / np.maximum(znorm, 1e-300)), 1.0)
    y *= clip[:, None]
    z *= clip[:, None]
    znorm *= clip

    w = p.weights
    y_w = w[: p.mu] @ y[: p.mu]
    mean = s.mean + p.c_m * s.sigma * y_w
    p_sigma = (1 - p.c_sigma) * s.p_sigma + math.sqrt(
        p.c_sigma * (2 - p.c_sigma) * p.mu_eff) * (w[: p.mu] @ z[: p.mu])
    ps_norm = float(np.linalg.norm(p_sigma))
    gen = s.generation + 1
    h_sigma = ps_norm / math.sqrt(1 - (1 - p.c_sigma) ** (2 * gen)) < (1.4 + 2 / (n + 1)) * p.chi_n
    p_c = (1 - p.c_c) * s.p_c + h_sigma * math.sqrt(p.c_c * (2 - p.c_c) * p.mu_eff) * y_w
    w_circ = np.where(w >= 0, w, w * n / np.maximum(znorm**2, 1e-300))
    w_circ[(w < 0) & changed[order]] = 0.0  # no active update from injected candidates
    delta_h = (1 - h_sigma) * p.c_c * (2 - p.c_c)
    C = ((1 + p.c_1 * delta_h - p.c_1 - p.c_mu * w.sum()) * s.C
         + p.c_1 * np.outer(p_c, p_c) + p.c_mu * (y.T * w_circ) @ y)
    sigma = s.sigma * math.exp(min(1.0, p.c_sigma / p.d_sigma * (ps_norm / p.chi_n - 1)))
    costs_sorted = cost[order]
    flat = costs_sorted[0] == costs_sorted[min(s.lam - 1, int(math.ceil(0.7 * s.lam)) - 1)]
    if flat:  # flat fitness: enlarge the step (tutorial, "flat fitness" note)
        sigma *= math.exp(0.2 + p.c_sigma / p.d_sigma)
    s = replace(s, mean=mean, sigma=sigma, C=C, p_sigma=p_sigma, p_c=p_c, generation=gen,
                best_hist=_push(s.best_hist, costs_sorted[0]),
                median_hist=_push(s.median_hist, float(np.median(costs_sorted))))
    if gen - s.eigen_generation >= p.eigen_every:
        s = _eigen(s, gen)

    reason = _stop_reason(opt, s, costs_sorted)
    if reason:
        return _restart(opt, s, reason, rng)
    if (opt.cfg.chaos and s.restart_jumps < opt.cfg.chaos_max_jumps
            and s.since_improvement >= opt.chaos_patience(s.lam)):
        s = _chaos_jump(opt, s)
    return s


def _chaos_jump(opt: CMAES, s: CMAESState) -> CMAESState:
    """Seed 002's Tent-map mean perturbation (see :mod:`evomotion.core.cmaes`, item 3)."""
    tent_x, delta_m = opt.chaos_step(s)
    delta_m[opt.fixed] = 0.0
    new_mean = s.mean + delta_m
    if opt.cfg.bound_handling == "reinject":
        new_mean = np.clip(new_mean, 0.0, 1.0)
    rms = float(np.sqrt(np.mean((new_mean - s.mean) ** 2)))
    n = opt.n
    return replace(s, mean=new_mean, tent_x=tent_x, p_sigma=np.zeros(n), p_c=np.zeros(n),
                   sigma=max(s.sigma, rms), since_improvement=0, restart_best=math.inf,
                   best_hist=np.zeros(0), median_hist=np.zeros(0), generation=0,
                   eigen_generation=0, chaos_jumps=s.chaos_jumps + 1,
                   restart_jumps=s.restart_jumps + 1)


def _push(hist: np.ndarray, value: float) -> np.ndarray:
    out = np.append(hist, value)
    return out[-MAX_HISTORY:]


def _eigen(s: CMAESState, gen: int) -> CMAESState:
    C = 0.5 * (s.C + s.C.T)
    evals, B = np.linalg.eigh(C)
    D = np.sqrt(np.maximum(evals, 1e-300))
    return replace(s, C=C, B=B, D=D, eigen_generation=gen)


def _stop_reason(opt: CMAES, s: CMAESState, costs_sorted: np.ndarray) -> str:
    """First termination criterion of the tutorial (appendix B.3) that holds, or ``""``."""
    n, lam, g, cfg = opt.n, s.lam, s.generation, opt.cfg
    hist_len = 10 + int(math.ceil(30 * n / lam))
    if g >= hist_len:
        recent = np.concatenate([s.best_hist[-hist_len:], costs_sorted])
        finite = recent[np.isfinite(recent)]
        if finite.size == recent.size and np.ptp(finite) < cfg.tolfun:
            return "tolfun"
    sd = s.sigma * np.sqrt(np.diag(s.C))
    if np.all(sd < cfg.tolx) and np.all(s.sigma * np.abs(s.p_c) < cfg.tolx):
        return "tolx"
    axis = g % n
    if np.all(s.mean == s.mean + 0.1 * s.sigma * s.D[axis] * s.B[:, axis]):
        return "noeffectaxis"
    if np.any(s.mean == s.mean + 0.2 * sd):
        return "noeffectcoord"
    if (s.D.max() / s.D.min()) ** 2 > CONDITION_LIMIT:
        return "conditioncov"
    stag = int(min(MAX_HISTORY, max(120 + 30 * n / lam, 0.2 * g)))
    if g >= stag:
        k = max(1, int(0.3 * stag))
        for h in (s.best_hist[-stag:], s.median_hist[-stag:]):
            if not np.median(h[-k:]) >= np.median(h[:k]):
                break
        else:
            return "tolstagnation"
    if g >= 100 + 150 * (n + 3) ** 2 / math.sqrt(lam):
        return "maxiter"
    if not np.all(np.isfinite(s.C)) or not math.isfinite(s.sigma) or s.sigma <= 0:
        return "numerical"
    return ""


def _restart(opt: CMAES, s: CMAESState, reason: str, rng: np.random.Generator) -> CMAESState:
    cfg = opt.cfg
    log = f"{s.stop_log};{reason}@{s.evaluations}" if s.stop_log else f"{reason}@{s.evaluations}"
    spent = s.evaluations - s.restart_evals0
    evals_large = s.evals_large + (spent if s.regime == "large" else 0)
    evals_small = s.evals_small + (spent if s.regime == "small" else 0)
    if cfg.restarts == "none" or s.restarts >= cfg.max_restarts:
        # no restart left: keep the distribution (only tolx may leave it degenerate)
        return replace(s, stop_reason=reason, stop_log=log, done=True,
                       evals_large=evals_large, evals_small=evals_small,
                       restart_evals0=s.evaluations)
    regime, large = "large", s.large_restarts
    sigma = cfg.sigma0
    if cfg.restarts == "ipop":
        lam = int(round(opt.lam0 * cfg.inc_popsize ** (s.restarts + 1)))
    elif evals_small < evals_large and large > 0:  # BIPOP small regime
        regime = "small"
        u = rng.uniform()
        lam_large = opt.lam0 * cfg.inc_popsize**large
        lam = max(2, int(opt.lam0 * (0.5 * lam_large / opt.lam0) ** (u * u)))
        sigma = cfg.sigma0 * 10 ** (-2 * u)
    else:
        large += 1
        lam = int(round(opt.lam0 * cfg.inc_popsize**large))
    fresh = opt.fresh_run(rng, lam, sigma)
    return replace(s, **fresh, restarts=s.restarts + 1, stop_reason=reason, stop_log=log,
                   regime=regime, large_restarts=large, evals_large=evals_large,
                   evals_small=evals_small, restart_evals0=s.evaluations)
