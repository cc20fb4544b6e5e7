"""Real-coded crossovers, vectorized over pairs of parents.

Every operator has the signature ``fn(a, b, rng, **params) -> children`` where ``a`` and ``b``
are ``[n, d]`` parent arrays (row ``i`` of ``a`` mates with row ``i`` of ``b``) and
``children`` is ``[k, n, d]``: ``k = 2`` children per pair, ``k = 3`` for Wright's linear
crossover (the GA keeps the best two of the three after evaluation). Results may leave the
bounds; the GA repairs them (see :func:`evomotion.core.operators.mutation.clip_to_bounds`).

Sources: one/two-point and uniform crossover (Goldberg 1989; Syswerda 1989); arithmetic
crossover (Michalewicz 1996, *Genetic Algorithms + Data Structures*); geometric crossover
(Michalewicz et al. 1996); linear crossover (Wright 1991, "Genetic algorithms for real
parameter optimization"); BLX-alpha (Eshelman & Schaffer 1993); SBX (Deb & Agrawal 1995);
beta-blend from paper 001 (section 3.2: ``(a1+a2+beta(a1-a2))/2``, ``(a1+a2+beta(a2-a1))/2``).
"""

from __future__ import annotations

from functools import partial

import numpy as np

from evomotion.core.registry import register

CROSSOVERS: dict = {}
_reg = partial(register, CROSSOVERS)


def _pair(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if a.shape != b.shape or a.ndim != 2:
        raise ValueError(f"parents must both be [n, d]; got {a.shape} and {b.shape}")
    return a, b


@_reg("one_point")
def one_point(a, b, rng: np.random.Generator) -> np.ndarray:
    """Swap the tails after a cut point drawn uniformly in ``1..d-1`` per pair."""
    a, b = _pair(a, b)
    n, d = a.shape
    if d < 2:
        return np.stack([a.copy(), b.copy()])
    cut = rng.integers(1, d, size=(n, 1))
    tail = np.arange(d)[None, :] >= cut
    return np.stack([np.where(tail, b, a), np.where(tail, a, b)])


@_reg("two_point")
def two_point(a, b, rng: np.random.Generator) -> np.ndarray:
    """Swap the segment between two distinct cut points."""
    a, b = _pair(a, b)
    n, d = a.shape
    if d < 3:
        return one_point(a, b, rng)
    cuts = np.sort(np.stack([rng.integers(1, d, n), rng.integers(1, d, n)], 1), axis=1)
    idx = np.arange(d)[None, :]
    mid = (idx >= cuts[:, :1]) & (idx < cuts[:, 1:])
    return np.stack([np.where(mid, b, a), np.where(mid, a, b)])


@_reg("uniform")
def uniform(a, b, rng: np.random.Generator, swap_prob: float = 0.5) -> np.ndarray:
    """Each gene is swapped independently with probability ``swap_prob``."""
    a, b = _pair(a, b)
    m = rng.random(a.shape) < swap_prob
    return np.stack([np.where(m, b, a), np.where(m, a, b)])


@_reg("arithmetic_whole")
def arithmetic_whole(a, b, rng: np.random.Generator) -> np.ndarray:
    """Whole arithmetic: ``c1 = l*a + (1-l)*b``, ``c2 = (1-l)*a + l*b``, ``l ~ U(0,1)`` per pair."""
    a, b = _pair(a, b)
    lam = rng.random((a.shape[0], 1))
    return np.stack([lam * a + (1 - lam) * b, (1 - lam) * a + lam * b])


@_reg("arithmetic_single")
def arithmetic_single(a, b, rng: np.random.Generator) -> np.ndarray:
    """Single arithmetic: one random gene per pair is blended; the rest are copied."""
    a, b = _pair(a, b)
    n, d = a.shape
    lam = rng.random((n, 1))
    gene = rng.integers(0, d, n)
    m = np.zeros((n, d), bool)
    m[np.arange(n), gene] = True
    c1 = np.where(m, lam * a + (1 - lam) * b, a)
    c2 = np.where(m, (1 - lam) * a + lam * b, b)
    return np.stack([c1, c2])


@_reg("geometric")
def geometric(a, b, rng: np.random.Generator) -> np.ndarray:
    """Geometric: ``c = a**w * b**(1-w)`` per gene (w ~ U(0,1) per pair).

    Defined for positive genes. Where a gene pair is not both positive, the sign-preserving
    form ``sign * |a|**w * |b|**(1-w)`` is used when both share a sign, and the arithmetic
    blend with the same weight otherwise (a geometric mean of mixed signs does not exist).
    """
    a, b = _pair(a, b)
    w = rng.random((a.shape[0], 1))
    same = np.sign(a) == np.sign(b)
    sgn = np.sign(a)
    with np.errstate(divide="ignore", invalid="ignore"):
        la, lb = np.log(np.abs(a)), np.log(np.abs(b))
        g1 = sgn * np.exp(w * la + (1 - w) * lb)
        g2 = sgn * np.exp((1 - w) * la + w * lb)
    ar1 = w * a + (1 - w) * b
    ar2 = (1 - w) * a + w * b
    zero = (a == 0) | (b == 0)
    ok = same & ~zero
    c1 = np.where(ok, g1, np.where(zero & same, 0.0, ar1))
    c2 = np.where(ok, g2, np.where(zero & same, 0.0, ar2))
    return np.stack([c1, c2])


@_reg("linear")
def linear(a, b, rng: np.random.Generator) -> np.ndarray:
    """Wright's three children ``(a+b)/2``, ``1.5a-0.5b``, ``-0.5a+1.5b`` (best two kept)."""
    a, b = _pair(a, b)
    return np.stack([0.5 * (a + b), 1.5 * a - 0.5 * b, -0.5 * a + 1.5 * b])


@_reg("blx_alpha")
def blx_alpha(a, b, rng: np.random.Generator, alpha: float = 0.5) -> np.ndarray:
    """BLX-alpha: each child gene ~ U(min - alpha*d, max + alpha*d), ``d = |a - b|``."""
    if alpha < 0:
        raise ValueError(f"blx_alpha needs alpha >= 0, got {alpha}")
    a, b = _pair(a, b)
    lo = np.minimum(a, b)
    width = np.abs(a - b)
    lo -= alpha * width
    width *= 1.0 + 2.0 * alpha
    u = rng.random((2,) + a.shape)
    u *= width
    u += lo
    return u


@_reg("sbx")
def sbx(a, b, rng: np.random.Generator, eta: float = 15.0) -> np.ndarray:
    """Simulated binary crossover with distribution index ``eta`` (unbounded form)."""
    if eta < 0:
        raise ValueError(f"sbx needs eta >= 0, got {eta}")
    a, b = _pair(a, b)
    u = rng.random(a.shape)
    beta = np.where(u <= 0.5, (2 * u) ** (1 / (eta + 1)), (1 / (2 * (1 - u))) ** (1 / (eta + 1)))
    c1 = 0.5 * ((1 + beta) * a + (1 - beta) * b)
    c2 = 0.5 * ((1 - beta) * a + (1 + beta) * b)
    return np.stack([c1, c2])


@_reg("beta_blend")
def beta_blend(a, b, rng: np.random.Generator, beta_max: float = 1.0) -> np.ndarray:
    """Paper 001's crossover: ``(a+b+beta(a-b))/2``, ``(a+b+beta(b-a))/2``, beta ~ U(0, beta_max).

    With ``beta_max <= 1`` both children lie on the segment between the parents.
    """
    a, b = _pair(a, b)
    beta = rng.uniform(0.0, beta_max, size=(a.shape[0], 1))
    return np.stack([(a + b + beta * (a - b)) / 2, (a + b + beta * (b - a)) / 2])
