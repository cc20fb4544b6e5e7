"""Mutations, vectorized over the population.

Signature: ``fn(x[n, d], lower[d], upper[d], rng, rate, **params) -> x'``. ``rate`` is the
probability that an *individual* is mutated (the papers' "mutation probability"); within a
mutated individual, ``gene_rate`` (default ``1/d``) or ``k`` chooses the genes. Results are
**clipped** into ``[lower, upper]`` (clipping keeps a gene on the bound it crossed, which
suits servo limits; see :func:`clip_to_bounds`).

Sources: uniform reset and Gaussian mutation (Michalewicz 1996; Eiben & Smith 2015, ch. 4);
``perturb_k`` is paper 000's mutation (Java appendix, ``mutate``: k random knots are shifted
by a uniform amount in ``[-delta, delta]``).
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np

from evomotion.core.registry import register

MUTATIONS: dict = {}
_reg = partial(register, MUTATIONS)


def clip_to_bounds(x: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                   out: np.ndarray | None = None) -> np.ndarray:
    """Clip every gene into its box; NaN genes become the lower bound (``out`` may be ``x``)."""
    y = np.maximum(x, lower, out=out)  # maximum propagates NaN ...
    np.minimum(y, upper, out=y)
    if math.isnan(np.add.reduce(y, axis=None)):  # ... so replace NaN genes explicitly
        # (one reduction when there are none; a ufunc reduce: no Python wrapper)
        nan = np.isnan(y)
        y[nan] = np.broadcast_to(lower, y.shape)[nan]
    return y


def _per_gene(bound, d: int) -> np.ndarray:
    """``bound`` as a ``[d]`` array (a view when it already is one: this runs per batch)."""
    if isinstance(bound, np.ndarray) and bound.shape == (d,):
        return bound
    return np.broadcast_to(bound, d)


def _who(rng: np.random.Generator, n: int, rate: float) -> np.ndarray:
    if not 0.0 <= rate <= 1.0:
        raise ValueError(f"mutation rate must be in [0, 1], got {rate}")
    return rng.random(n) < rate


def _positions(rng: np.random.Generator, who: np.ndarray, d: int,
               gene_rate: float | None) -> tuple[np.ndarray, np.ndarray]:
    """Row/column indices of the genes to mutate.

    Each gene of a mutated individual (``who``) is chosen with probability ``gene_rate``
    (default ``1/d``), and at least one gene is forced per mutated individual. For small
    rates the Bernoulli process is sampled sparsely through geometric gaps between hits,
    so the cost is proportional to the number of mutated genes, not to ``n * d``.
    """
    n = who.size
    p = 1.0 / d if gene_rate is None else float(gene_rate)
    if not 0.0 <= p <= 1.0:
        raise ValueError(f"gene_rate must be in [0, 1], got {p}")
    total = n * d
    if p >= 0.2 or total == 0:
        flat = np.flatnonzero(rng.random(total) < p)
    elif p == 0.0:
        flat = np.empty(0, dtype=np.int64)
    else:
        mean = total * p
        size = int(mean + 6 * math.sqrt(mean) + 16)
        pos = np.cumsum(rng.geometric(p, size=size)) - 1
        while pos[-1] < total - 1:  # rare: extend the process until it passes the end
            pos = np.concatenate([pos, pos[-1] + np.cumsum(rng.geometric(p, size=size))])
        flat = pos[pos < total]
    rows, cols = np.divmod(flat, d)
    keep = who[rows]
    rows, cols = rows[keep], cols[keep]
    forced = np.flatnonzero(who & (np.bincount(rows, minlength=n) == 0))
    fcols = rng.integers(0, d, forced.size)
    return np.concatenate([rows, forced]), np.concatenate([cols, fcols])


@_reg("uniform_reset")
def uniform_reset(x, lower, upper, rng: np.random.Generator, rate: float,
                  gene_rate: float | None = None) -> np.ndarray:
    """Reset chosen genes to ``U(lower, upper)``."""
    x = np.array(x, dtype=float)
    r, c = _positions(rng, _who(rng, x.shape[0], rate), x.shape[1], gene_rate)
    lower, upper = _per_gene(lower, x.shape[1]), _per_gene(upper, x.shape[1])
    x[r, c] = rng.uniform(lower[c], upper[c])
    return x


@_reg("gaussian")
def gaussian(x, lower, upper, rng: np.random.Generator, rate: float,
             sigma: float = 0.1, gene_rate: float | None = None) -> np.ndarray:
    """Add ``N(0, (sigma * (upper - lower))^2)`` to chosen genes (sigma: fraction of range)."""
    if sigma < 0:
        raise ValueError(f"gaussian mutation needs sigma >= 0, got {sigma}")
    x = np.array(x, dtype=float)
    r, c = _positions(rng, _who(rng, x.shape[0], rate), x.shape[1], gene_rate)
    lower, upper = _per_gene(lower, x.shape[1]), _per_gene(upper, x.shape[1])
    v = x[r, c] + rng.standard_normal(r.size) * (sigma * (upper[c] - lower[c]))
    x[r, c] = np.clip(v, lower[c], upper[c])
    return x


@_reg("perturb_k")
def perturb_k(x, lower, upper, rng: np.random.Generator, rate: float,
              k: int = 1, delta: float = 0.1) -> np.ndarray:
    """Paper 000: shift ``k`` distinct random genes by ``U(-delta, delta)`` (``delta`` as a
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
