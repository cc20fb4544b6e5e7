"""Lévy-flight steps by Mantegna's algorithm (paper 002, section 2.3).

R. N. Mantegna, "Fast, accurate algorithm for numerical simulation of Lévy stable stochastic
processes", Phys. Rev. E 49(5):4677-4683 (1994); the form used in cuckoo search (Yang & Deb
2009) and in paper 002::

    s = u / |v|^(1/beta),   u ~ N(0, sigma_u^2),  v ~ N(0, 1),
    sigma_u = [ Gamma(1 + beta) sin(pi beta / 2)
                / (Gamma((1 + beta) / 2) beta 2^((beta - 1) / 2)) ]^(1 / beta)

with ``beta = 1.5`` by default. ``|s|`` has a power-law tail ``P(|s| > x) ~ x^(-beta)``, so
large jumps are much more likely than for a Gaussian. A Lévy flight moves a point by
``x' = x + alpha (.) s`` (element-wise product ``(.)``, step control ``alpha``); how the step
enters the CMA-ES candidates is documented in :mod:`evomotion.core.cmaes`.
"""

from __future__ import annotations

import math

import numpy as np


def mantegna_sigma_u(beta: float) -> float:
    """Scale ``sigma_u`` of the numerator Gaussian for stability index ``beta`` (0 < beta <= 2)."""
    if not 0.0 < beta <= 2.0:
        raise ValueError(f"Lévy index beta must be in (0, 2], got {beta}")
    num = math.gamma(1.0 + beta) * math.sin(math.pi * beta / 2.0)
    den = math.gamma((1.0 + beta) / 2.0) * beta * 2.0 ** ((beta - 1.0) / 2.0)
    return (num / den) ** (1.0 / beta)


def mantegna_steps(rng: np.random.Generator, shape: tuple[int, ...] | int,
                   beta: float = 1.5) -> np.ndarray:
    """Lévy-distributed steps ``s`` of the given shape (dimensionless)."""
    sigma_u = mantegna_sigma_u(beta)
    u = rng.normal(0.0, sigma_u, size=shape)
    v = rng.standard_normal(size=shape)
    return u / np.abs(v) ** (1.0 / beta)


def levy_flight(x: np.ndarray, alpha: np.ndarray | float, rng: np.random.Generator,
                beta: float = 1.5) -> np.ndarray:
    """Paper 002's update ``x' = x + alpha (.) Levy(beta)`` for each row of ``x``."""
    x = np.asarray(x, dtype=float)
    return x + np.asarray(alpha, dtype=float) * mantegna_steps(rng, x.shape, beta)
