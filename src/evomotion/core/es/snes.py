"""SNES: Schaul, Glasmachers & Schmidhuber 2011, "High dimensions and heavy tails for natural
evolution strategies" (GECCO 2011), Algorithm "SNES" (separable NES), with the utilities
and default learning rates of that paper (also in Wierstra et al. 2014, "Natural Evolution
Strategies", JMLR 15).

A Gaussian with diagonal covariance ``N(μ, diag(σ²))``: O(d) per sample, meant for
``d >= 1000`` parameters where full covariance is too costly. One generation:

1. ``ask``: ``s_k ~ N(0, I)``, ``k = 1..λ`` (one call, or windows of the shared noise table
   with ``noise_table > 0``); ``z_k = μ + σ s_k``, clipped into the bounds (see
   :mod:`~evomotion.core.es.common`).
2. ``tell``: utilities ``u_k`` by rank (:func:`~evomotion.core.es.ranking.nes_utilities`);
   ``s_k`` is recomputed from the evaluated ``z_k`` as ``(z_k - μ) / σ``.
3. Natural gradients: ``∇_μ J = Σ_k u_k s_k``, ``∇_σ J = Σ_k u_k (s_k² - 1)``.
4. Updates: ``μ ← μ + η_μ σ ∇_μ J``, ``σ ← σ exp(η_σ / 2 ∇_σ J)``.

Defaults from the paper: ``λ = 4 + ⌊3 ln d⌋`` (``pop_size = 0``), ``η_μ = 1``,
``η_σ = (3 + ln d) / (5 √d)`` (``sigma_learning_rate = 0``). ``σ`` starts at
``sigma_init`` (genome units) on every parameter; ``μ`` at the middle of the bounds or at
row 0 of ``init``'s population. ``center(state)`` is ``μ``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from evomotion.core.es.common import (
    GaussianES,
    check_noise_table,
    check_nonneg,
    check_pop_size,
    check_positive,
)
from evomotion.core.es.ranking import nes_utilities
from evomotion.core.optimizer import MutateFn
from evomotion.core.problem import GenomeSpec
from evomotion.core.state import replaced as replace


@dataclass(frozen=True)
class SNESConfig:
    """Settings of SNES (``[algorithm]`` with ``name = "snes"``)."""

    name: str = "snes"
    pop_size: int = 0  # λ; 0 -> 4 + floor(3 ln d)
    sigma_init: float = 0.1  # initial σ of every parameter, genome units
    center_learning_rate: float = 1.0  # η_μ
    sigma_learning_rate: float = 0.0  # η_σ; 0 -> (3 + ln d) / (5 sqrt(d))
    noise_table: int = 0  # > 0: s_k from a shared table of this many N(0, 1) numbers

    def validate(self) -> None:
        check_pop_size(self, even=False, allow_zero=True)
        check_noise_table(self)
        check_positive(self, "sigma_init", "center_learning_rate")
        check_nonneg(self, "sigma_learning_rate")


def default_lambda(d: int) -> int:
    return 4 + int(math.floor(3 * math.log(max(d, 1))))


def default_eta_sigma(d: int) -> float:
    return (3 + math.log(max(d, 1))) / (5 * math.sqrt(max(d, 1)))


@dataclass
class SNESState:
    center: np.ndarray  # μ [d]
    sigma: np.ndarray  # σ [d]
    pop: np.ndarray  # the last told genomes [λ, d]
    cost: np.ndarray  # their costs
    best_x: np.ndarray
    best_cost: float
    generation: int = 0


class SNES(GaussianES):
    """Separable NES (Schaul et al. 2011): diagonal covariance, rank utilities."""

    name = "snes"
    cfg: SNESConfig

    def __init__(self, genome: GenomeSpec, cfg: SNESConfig, *,
                 mutate: MutateFn | None = None) -> None:
        super().__init__(genome, cfg, mutate=mutate)
        d = genome.dim
        self.lam = cfg.pop_size or default_lambda(d)
        self.eta_sigma = cfg.sigma_learning_rate or default_eta_sigma(d)

    def expected_population(self) -> int | None:
        """λ (the default ``4 + floor(3 ln d)`` when ``pop_size`` is 0)."""
        return self.lam

    def init(self, rng: np.random.Generator, population: np.ndarray | None = None) -> SNESState:
        c = self.start_center(population)
        return SNESState(center=c, sigma=np.full(self.genome.dim, self.cfg.sigma_init),
                         pop=np.repeat(c[None], self.lam, axis=0),
                         cost=np.full(self.lam, np.inf), best_x=c.copy(), best_cost=math.inf)

    def _ask(self, state: SNESState, rng: np.random.Generator) -> tuple[np.ndarray, SNESState]:
        z = self.scaled_normal(rng, state.sigma, np.empty((self.lam, self.genome.dim)))  # σ s_k
        inside = not self.bounded or self._inside(state.center, z)
        z += state.center  # z_k = μ + σ s_k
        return (z if inside else self.clip(z)), state

    def _tell(self, state: SNESState, genomes: np.ndarray, cost: np.ndarray,
              rng: np.random.Generator, measures: np.ndarray | None = None) -> SNESState:
        self.check_told(genomes)
        u = nes_utilities(cost)
        s = genomes - state.center
        s /= state.sigma  # s_k as evaluated
        grad_mu = u @ s  # ∇_μ J = Σ u_k s_k
        s *= s
        grad_sigma = u @ s - u.sum()  # ∇_σ J = Σ u_k (s_k² - 1)
        center = state.center + self.cfg.center_learning_rate * state.sigma * grad_mu
        sigma = state.sigma * np.exp(0.5 * self.eta_sigma * grad_sigma)
        return replace(state, center=self.clip(center), sigma=sigma,
                       pop=np.array(genomes, dtype=float), cost=cost.copy())


def make_snes(genome: GenomeSpec, cfg: SNESConfig, *, mutate: MutateFn | None = None) -> SNES:
    """Factory for the ``ALGORITHMS`` registry (``"snes"``); ``mutate`` must be ``None``."""
    return SNES(genome, cfg, mutate=mutate)
