"""Mutations, vectorized over the population.

Signature: ``fn(x[n, d], lower[d], upper[d], rng, rate, **params) -> x'``. ``rate`` is the
probability that an *individual* is mutated (the seeds' "mutation probability"); within a
mutated individual, ``gene_rate`` (default ``1/d``) or ``k`` chooses the genes. Results are
**clipped** into ``[lower, upper]`` (clipping keeps a gene on the bound it crossed, which
suits servo limits; see :func:`clip_to_bounds`).

Sources: uniform reset and Gaussian mutation (Michalewicz 1996; Eiben & Smith 2015, ch. 4);
``perturb_k`` is seed 000's mutation (Java appendix, ``mutate``: k random knots are shifted
by a uniform amount in ``[-delta, delta]``).
"""

from __future__ import annotations

import numpy as np

MUTATIONS: dict = {}


def _reg(name: str):
    def deco(fn):
        MUTATIONS[name] = fn
        return fn
    return deco


def clip_to_bounds(x: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Clip every gene into its box (NaN genes become the lower bound)."""
    x = np.where(np.isnan(x), lower, x)
    return np.clip(x, lower, upper)


def _who(rng: np.random.Generator, n: int, rate: float) -> np.ndarray:
    if not 0.0 <= rate <= 1.0:
        raise ValueError(f"mutation rate must be in [0, 1], got {rate}")
    return rng.random(n) < rate


def _gene_mask(rng, shape, gene_rate):
    n, d = shape
    p = 1.0 / d if gene_rate is None else float(gene_rate)
    m = rng.random(shape) < p
    # at least one gene changes in a mutated individual
    force = rng.integers(0, d, n)
    m[np.arange(n), force] = True
    return m


@_reg("uniform_reset")
def uniform_reset(x, lower, upper, rng: np.random.Generator, rate: float,
                  gene_rate: float | None = None) -> np.ndarray:
    """Reset chosen genes to ``U(lower, upper)``."""
    x = np.array(x, dtype=float)
    who = _who(rng, x.shape[0], rate)
    mask = _gene_mask(rng, x.shape, gene_rate) & who[:, None]
    fresh = rng.uniform(lower, upper, size=x.shape)
    return np.where(mask, fresh, x)


@_reg("gaussian")
def gaussian(x, lower, upper, rng: np.random.Generator, rate: float,
             sigma: float = 0.1, gene_rate: float | None = None) -> np.ndarray:
    """Add ``N(0, (sigma * (upper - lower))^2)`` to chosen genes (sigma: fraction of range)."""
    if sigma < 0:
        raise ValueError(f"gaussian mutation needs sigma >= 0, got {sigma}")
    x = np.array(x, dtype=float)
    who = _who(rng, x.shape[0], rate)
    mask = _gene_mask(rng, x.shape, gene_rate) & who[:, None]
    step = rng.standard_normal(x.shape) * (sigma * (np.asarray(upper) - np.asarray(lower)))
    return clip_to_bounds(np.where(mask, x + step, x), lower, upper)


@_reg("perturb_k")
def perturb_k(x, lower, upper, rng: np.random.Generator, rate: float,
              k: int = 1, delta: float = 0.1) -> np.ndarray:
    """Seed 000: shift ``k`` distinct random genes by ``U(-delta, delta)`` (``delta`` as a
    fraction of each gene's range)."""
    x = np.array(x, dtype=float)
    n, d = x.shape
    if not 1 <= k <= d:
        raise ValueError(f"perturb_k needs 1 <= k <= {d}, got {k}")
    who = _who(rng, n, rate)
    # k distinct genes per row: the k smallest of d uniform keys
    keys = rng.random((n, d))
    chosen = np.argpartition(keys, k - 1, axis=1)[:, :k] if k < d else np.tile(np.arange(d), (n, 1))
    mask = np.zeros((n, d), bool)
    mask[np.arange(n)[:, None], chosen] = True
    mask &= who[:, None]
    step = rng.uniform(-delta, delta, size=(n, d)) * (np.asarray(upper) - np.asarray(lower))
    return clip_to_bounds(np.where(mask, x + step, x), lower, upper)
