"""Tent chaotic map used by the improved CMA-ES of paper 002 to perturb the mean.

The Tent map (e.g. Kuo & Kuo; Shan et al. 2005, "Chaotic optimization algorithm based on Tent
map") with slope ``mu``::

    x_{k+1} = mu * x_k          if x_k < 0.5
    x_{k+1} = mu * (1 - x_k)    otherwise,          1 < mu < 2, x_k in [0, 1].

For ``1 < mu < 2`` every orbit from ``0 < x0 < 1`` enters the invariant interval
``[a, b] = [mu (1 - mu / 2), mu / 2]`` and is chaotic there (Lyapunov exponent ``ln mu > 0``),
except at the fixed points ``0`` and ``mu / (1 + mu)``. The paper requires ``x0 != mu``; we also
reject the fixed points, whose orbits are periodic (period 1).

Paper 002 maps the chaotic variable into the search range ``[L_d, U_d]`` of each dimension.
Because for ``mu < 2`` the orbit only covers ``[a, b]``, :func:`tent_to_box` first stretches
``[a, b]`` onto ``[0, 1]`` and then onto ``[L_d, U_d]``, so the chaotic points reach the whole box.
How the point enters the CMA-ES mean (``Delta m_d``) is documented in :mod:`evomotion.core.cmaes`.
"""

from __future__ import annotations

import numpy as np


def validate_tent(mu: float, x0: np.ndarray | float) -> None:
    """Raise ``ValueError`` unless ``1 < mu < 2`` and every ``x0`` gives a chaotic orbit."""
    if not 1.0 < mu < 2.0:
        raise ValueError(f"Tent map slope mu must satisfy 1 < mu < 2, got {mu}")
    x = np.atleast_1d(np.asarray(x0, dtype=float))
    if np.any((x <= 0.0) | (x >= 1.0)):
        raise ValueError("Tent map start x0 must lie in the open interval (0, 1)")
    fixed = mu / (1.0 + mu)
    if np.any(np.isclose(x, fixed, rtol=0, atol=1e-12)) or np.any(x == mu):
        raise ValueError(f"Tent map start x0 must differ from mu and from the fixed point {fixed}")


def tent_interval(mu: float) -> tuple[float, float]:
    """Invariant interval ``[mu (1 - mu/2), mu/2]`` of the Tent map for ``1 < mu < 2``."""
    return mu * (1.0 - mu / 2.0), mu / 2.0


def tent_map(x: np.ndarray, mu: float) -> np.ndarray:
    """One Tent-map iteration, element-wise."""
    x = np.asarray(x, dtype=float)
    return np.where(x < 0.5, mu * x, mu * (1.0 - x))


def tent_sequence(x0: np.ndarray | float, mu: float, n: int) -> np.ndarray:
    """``n`` iterates ``x_1..x_n`` from ``x0`` (shape ``[n, *x0.shape]``)."""
    validate_tent(mu, x0)
    x = np.asarray(x0, dtype=float)
    out = np.empty((n, *x.shape))
    for k in range(n):
        x = tent_map(x, mu)
        out[k] = x
    return out


def tent_to_box(x: np.ndarray, mu: float, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Chaotic point ``c_d = L_d + (U_d - L_d) * (x_d - a) / (b - a)``, clipped to ``[L_d, U_d]``.

    ``[a, b]`` is the invariant interval; an iterate still in its transient (outside ``[a, b]``)
    is clipped to the box edge.
    """
    a, b = tent_interval(mu)
    u = np.clip((np.asarray(x, dtype=float) - a) / (b - a), 0.0, 1.0)
    return lower + (upper - lower) * u
