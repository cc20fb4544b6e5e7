"""Termination criteria of one CMA-ES run (before a restart), and the histories they read.

Source: N. Hansen, "The CMA Evolution Strategy: A Tutorial", arXiv:1604.00772, appendix B.3
(tolfun, tolx, noeffectaxis, noeffectcoord, conditioncov, tolstagnation, maxiter), in the
order checked there; ``numerical`` catches a non-finite covariance or step size. ``g`` is the
generation within the run (``state.restart_generation``), all lengths in normalised units.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from evomotion.core.cmaes import CMAESConfig, CMAESState

MAX_HISTORY = 20000  # longest best/median cost history kept (bounds tolstagnation's window)
CONDITION_LIMIT = 1e14  # conditioncov: largest condition number of C


def push_history(hist: np.ndarray, value: float) -> np.ndarray:
    """``hist`` with ``value`` appended, the last :data:`MAX_HISTORY` entries."""
    return np.append(hist, value)[-MAX_HISTORY:]


def tolfun_window(n: int, lam: int) -> int:
    """Generations over which tolfun compares costs: ``10 + ceil(30 n / lambda)``."""
    return 10 + int(math.ceil(30 * n / lam))


def _tolfun(cfg: CMAESConfig, s: CMAESState, costs_sorted: np.ndarray) -> bool:
    """The range of the best costs of the last generations and of all current costs is
    below ``tolfun``."""
    window = tolfun_window(s.mean.size, s.lam)
    if s.restart_generation < window:
        return False
    recent = np.concatenate([s.best_hist[-window:], costs_sorted])
    finite = recent[np.isfinite(recent)]
    return bool(finite.size == recent.size and np.ptp(finite) < cfg.tolfun)


def _tolstagnation(s: CMAESState) -> bool:
    """Over the last ``120 + 30 n / lambda`` (at least ``0.2 g``) generations, the median of
    neither the best nor the median costs of the last 30% improved on the first 30%."""
    n, g = s.mean.size, s.restart_generation
    stag = int(min(MAX_HISTORY, max(120 + 30 * n / s.lam, 0.2 * g)))
    if g < stag:
        return False
    k = max(1, int(0.3 * stag))
    return all(np.median(h[-k:]) >= np.median(h[:k])
               for h in (s.best_hist[-stag:], s.median_hist[-stag:]))


def stop_reason(cfg: CMAESConfig, s: CMAESState, costs_sorted: np.ndarray) -> str:
    """First criterion that holds after the update of generation ``g``, or ``""``."""
    n, lam, g = s.mean.size, s.lam, s.restart_generation
    sd = s.sigma * np.sqrt(np.diag(s.C))  # standard deviation per coordinate
    axis = g % n  # noeffectaxis checks one principal axis per generation
    if _tolfun(cfg, s, costs_sorted):
        return "tolfun"
    if np.all(sd < cfg.tolx) and np.all(s.sigma * np.abs(s.p_c) < cfg.tolx):
        return "tolx"
    if np.all(s.mean == s.mean + 0.1 * s.sigma * s.D[axis] * s.B[:, axis]):
        return "noeffectaxis"
    if np.any(s.mean == s.mean + 0.2 * sd):
        return "noeffectcoord"
    if (s.D.max() / s.D.min()) ** 2 > CONDITION_LIMIT:
        return "conditioncov"
    if _tolstagnation(s):
        return "tolstagnation"
    if g >= 100 + 150 * (n + 3) ** 2 / math.sqrt(lam):
        return "maxiter"
    if not np.all(np.isfinite(s.C)) or not math.isfinite(s.sigma) or s.sigma <= 0:
        return "numerical"
    return ""
