"""Finger -> target matching and tip distances of paper 001 (section 3.3) and its proposed fix.

``D[n, F, T]`` holds the distance of finger ``f``'s tip to target ``t`` (straight line, or the
way around the obstacles from :mod:`.visibility`). An assignment ``a[n, F]`` gives each finger a
distinct target; the objective is ``sum_f D[f, a_f]``.

- ``greedy``: the paper's matching, repeatedly taking the closest remaining (finger, target) pair.
- ``optimal``: the minimum-sum assignment (Hungarian method, ``scipy.optimize.
  linear_sum_assignment``); for up to 6 fingers the same optimum is found by scoring all
  ``F!`` permutations at once, vectorized over the population.
- ``chromosome``: the paper's suggested fix (section 5), one random key per finger in the genome;
  finger ``f`` gets target ``argsort(keys)[f]``, so crossover and mutation carry the matching.
"""

from __future__ import annotations

import itertools
from functools import lru_cache

import numpy as np
from scipy.optimize import linear_sum_assignment

MATCHINGS = ("greedy", "optimal", "chromosome")
DISTANCES = ("straight", "obstacle")


def straight_distances(tips: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """``(n, F, T)`` Euclidean distances of tips ``(n, F, 2)`` to targets ``(T, 2)``."""
    return np.linalg.norm(tips[:, :, None, :] - targets[None, None], axis=-1)


def greedy_match(D: np.ndarray) -> np.ndarray:
    """Paper's greedy matching: ``F`` rounds of taking the globally closest free pair."""
    n, F, T = D.shape
    work = np.where(np.isfinite(D), D, 1e300)  # free pairs stay finite, taken ones become inf
    assign = np.zeros((n, F), dtype=int)
    rows = np.arange(n)
    for _ in range(F):
        f, t = np.divmod(np.argmin(work.reshape(n, -1), axis=1), T)
        assign[rows, f] = t
        work[rows, f, :] = np.inf
        work[rows, :, t] = np.inf
    return assign


@lru_cache(maxsize=8)
def _perms(F: int) -> np.ndarray:
    return np.array(list(itertools.permutations(range(F))), dtype=int)


def optimal_match(D: np.ndarray) -> np.ndarray:
    """Minimum-sum assignment per individual (ties broken by the first permutation)."""
    n, F, T = D.shape
    Dc = np.where(np.isfinite(D), D, 1e300)
    if F == T and F <= 6:
        perms = _perms(F)  # (P, F)
        tot = Dc[:, np.arange(F), perms].sum(axis=-1)  # (n, P)
        return perms[np.argmin(tot, axis=1)]
    out = np.zeros((n, F), dtype=int)
    for i in range(n):  # scipy has no batched Hungarian; only for > 6 fingers
        r, c = linear_sum_assignment(Dc[i])
        out[i, r] = c
    return out


def keys_match(keys: np.ndarray) -> np.ndarray:
    """Random-key decoding: finger ``f`` gets target ``argsort(keys)[f]``."""
    return np.argsort(keys, axis=1, kind="stable")


def matched(D: np.ndarray, assign: np.ndarray) -> np.ndarray:
    """``D[i, f, assign[i, f]]`` as ``(n, F)``."""
    return np.take_along_axis(D, assign[..., None], axis=2)[..., 0]
