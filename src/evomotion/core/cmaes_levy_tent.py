"""Paper 002's improvements inside CMA-ES: Lévy-flight candidates and Tent-map mean jumps.

Source: Zhou & Liang 2023 (paper 002), sections 2.2-2.3; the maps themselves are in
:mod:`evomotion.core.levy` (Mantegna 1994) and :mod:`evomotion.core.chaos` (Tent map). How
they enter a generation is described in :mod:`evomotion.core.cmaes` (items 1 and 3). Both
are switched by the config (``levy``, ``chaos``); pure functions of the frozen config, the
mask of fixed genes and the state.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from evomotion.core.chaos import tent_map, tent_to_box
from evomotion.core.cmaes_stop import tolfun_window
from evomotion.core.levy import mantegna_steps

if TYPE_CHECKING:
    from evomotion.core.cmaes import CMAESConfig, CMAESState


def tent_start(cfg: CMAESConfig, rng: np.random.Generator, n: int) -> np.ndarray:
    """Initial chaos state per dimension, ``U(0.05, 0.95)`` off the map's fixed point."""
    tent0 = rng.uniform(0.05, 0.95, n)
    if cfg.chaos:
        fixed = cfg.chaos_mu / (1 + cfg.chaos_mu)
        tent0 = np.where(np.abs(tent0 - fixed) < 1e-9, tent0 + 1e-3, tent0)
    return tent0


def levy_candidates(cfg: CMAESConfig, s: CMAESState, u: np.ndarray,
                    rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``(u', rows)``: a random ``round(levy_fraction * lambda)`` (at least one) of the
    sampled candidates ``u`` moved by ``alpha sigma B (D (.) s)``, ``s`` Mantegna steps."""
    lam, n = u.shape
    k = max(1, int(round(cfg.levy_fraction * lam)))
    rows = rng.choice(lam, size=k, replace=False)
    s_levy = mantegna_steps(rng, (k, n), cfg.levy_beta)
    u = u.copy()
    u[rows] += cfg.levy_alpha * s.sigma * (s_levy * s.D) @ s.B.T
    return u, rows


def chaos_patience(cfg: CMAESConfig, n: int, lam: int) -> int:
    """Generations without improvement before a jump (default: the tolfun window)."""
    return cfg.chaos_patience or tolfun_window(n, lam)


def chaos_due(cfg: CMAESConfig, s: CMAESState) -> bool:
    """Whether the run has stagnated long enough for a jump, with jumps left this restart."""
    return (cfg.chaos and s.restart_jumps < cfg.chaos_max_jumps
            and s.since_improvement >= chaos_patience(cfg, s.mean.size, s.lam))


def chaos_jump(cfg: CMAESConfig, fixed: np.ndarray, s: CMAESState) -> CMAESState:
    """Move the mean by ``chaos_strength (c - m)``, ``c`` the next Tent point in the box;
    reset the paths and the stagnation histories, ``sigma >= rms(Delta m)``."""
    n = s.mean.size
    tent_x = tent_map(s.tent_x, cfg.chaos_mu)
    c = tent_to_box(tent_x, cfg.chaos_mu, np.zeros(n), np.ones(n))
    delta_m = cfg.chaos_strength * (c - s.mean)
    delta_m[fixed] = 0.0
    new_mean = s.mean + delta_m
    if cfg.bound_handling == "reinject":
        new_mean = np.clip(new_mean, 0.0, 1.0)
    rms = float(np.sqrt(np.mean((new_mean - s.mean) ** 2)))
    return replace(s, mean=new_mean, tent_x=tent_x, p_sigma=np.zeros(n), p_c=np.zeros(n),
                   sigma=max(s.sigma, rms), since_improvement=0, restart_best=math.inf,
                   best_hist=np.zeros(0), median_hist=np.zeros(0), restart_generation=0,
                   eigen_generation=0, chaos_jumps=s.chaos_jumps + 1,
                   restart_jumps=s.restart_jumps + 1)
