"""PGPE with ClipUp: Sehnke, Osendorfer, Rückstieß, Graves, Peters & Schmidhuber 2010,
"Parameter-exploring policy gradients" (Neural Networks 23(4)), with the centre stepped by
ClipUp and centred-rank fitness shaping as in Toklu, Liskowski & Srivastava 2020 (ClipUp,
arXiv:2008.02387).

One generation (Sehnke et al. 2010, PGPE with symmetric sampling; rewards are utilities
``u``, larger for a lower cost):

1. ``ask``: ``N = pop_size / 2`` perturbations ``ε_k ~ N(0, diag(σ²))`` (one
   ``standard_normal`` call scaled by the per-parameter ``σ``); the symmetric pair
   ``μ + ε_k`` (row ``k``) and ``μ - ε_k`` (row ``k + N``), clipped into the bounds (see
   :mod:`~evomotion.core.es.common`).
2. ``tell``: ``u`` = centred ranks of all ``2N`` costs (Toklu et al. 2020, their fitness
   shaping; :func:`~evomotion.core.es.ranking.centered_ranks`).
3. Centre gradient (Sehnke et al. 2010, the symmetric-sampling update of ``μ``):
   ``∇_μ = 1/N Σ_k ε_k (u_k+ - u_k-) / 2``, followed by one ClipUp step
   (:mod:`~evomotion.core.es.clipup`: step size ``center_learning_rate``, default
   ``0.5 max_speed``; momentum 0.9; velocity norm ``<= max_speed``).
4. Std gradient (Sehnke et al. 2010, the symmetric-sampling update of ``σ``
   with the baseline ``b``):
   ``∇_σ = 1/N Σ_k ((u_k+ + u_k-) / 2 - b) (ε_k² - σ²) / σ`` with ``b`` the mean of
   ``(u_k+ + u_k-) / 2`` (0 up to rounding for centred ranks);
   ``σ' = σ + stdev_learning_rate ∇_σ``, then bounded per parameter to
   ``[σ (1 - stdev_max_change), σ (1 + stdev_max_change)]`` (the relative bound on the
   std's change used with ClipUp by Toklu et al. and EvoTorch).

``σ`` starts at ``stdev_init`` (genome units) on every parameter. The centre starts at the
middle of the bounds or at row 0 of ``init``'s population. ``center(state)`` is ``μ``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from evomotion.core.es.clipup import clipup_step
from evomotion.core.es.common import (
    GaussianES,
    check_noise_table,
    check_nonneg,
    check_pop_size,
    check_positive,
    check_unit,
    half_differences,
)
from evomotion.core.es.ranking import centered_ranks
from evomotion.core.optimizer import MutateFn
from evomotion.core.problem import GenomeSpec
from evomotion.core.state import replaced as replace


@dataclass(frozen=True)
class PGPEConfig:
    """Settings of PGPE with ClipUp (``[algorithm]`` with ``name = "pgpe"``)."""

    name: str = "pgpe"
    pop_size: int = 100  # 2N: N symmetric pairs (even)
    max_speed: float = 0.15  # ClipUp's v_max: the largest centre step, genome units
    center_learning_rate: float = 0.0  # ClipUp's α; 0 -> 0.5 * max_speed
    momentum: float = 0.9  # ClipUp's m
    stdev_init: float = 0.1  # initial σ of every parameter, genome units
    stdev_learning_rate: float = 0.1
    stdev_max_change: float = 0.2  # σ changes by at most this fraction per generation
    noise_table: int = 0  # > 0: perturbations from a shared table of this many N(0, 1) numbers

    def validate(self) -> None:
        check_pop_size(self, even=True)
        check_noise_table(self)
        check_positive(self, "max_speed", "stdev_init", "stdev_max_change")
        check_nonneg(self, "center_learning_rate", "stdev_learning_rate")
        check_unit(self, "momentum", "stdev_max_change")

    @property
    def step_size(self) -> float:
        """ClipUp's step size α: ``center_learning_rate`` or ``0.5 max_speed``."""
        return self.center_learning_rate or 0.5 * self.max_speed


@dataclass
class PGPEState:
    center: np.ndarray  # μ [d]
    stdev: np.ndarray  # σ [d]
    velocity: np.ndarray  # ClipUp's v [d]
    pop: np.ndarray  # the last told genomes [2N, d]
    cost: np.ndarray  # their costs
    best_x: np.ndarray
    best_cost: float
    generation: int = 0


def pgpe_gradients(u_plus: np.ndarray, u_minus: np.ndarray, eps: np.ndarray,
                   stdev: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(∇_μ, ∇_σ)`` of symmetric sampling (Sehnke et al. 2010) from the
    utilities of the pairs and their perturbations ``ε_k`` (rows; squared in place)."""
    n = eps.shape[0]
    grad_mu: np.ndarray = ((u_plus - u_minus) @ eps) / (2 * n)
    avg = 0.5 * (u_plus + u_minus)
    w = avg - avg.mean()  # the baseline b
    eps *= eps
    # Σ_k w_k (ε_k² - σ²) / σ = (Σ w_k ε_k² - σ² Σ w_k) / σ
    grad_sigma: np.ndarray = ((w @ eps) - stdev * stdev * w.sum()) / (n * stdev)
    return grad_mu, grad_sigma


class PGPE(GaussianES):
    """PGPE (Sehnke et al. 2010) with ClipUp (Toklu et al. 2020) and centred ranks."""

    name = "pgpe"
    cfg: PGPEConfig

    def init(self, rng: np.random.Generator, population: np.ndarray | None = None) -> PGPEState:
        c = self.start_center(population)
        n, d = self.cfg.pop_size, self.genome.dim
        return PGPEState(center=c, stdev=np.full(d, self.cfg.stdev_init), velocity=np.zeros(d),
                         pop=np.repeat(c[None], n, axis=0), cost=np.full(n, np.inf),
                         best_x=c.copy(), best_cost=math.inf)

    def _ask(self, state: PGPEState, rng: np.random.Generator) -> tuple[np.ndarray, PGPEState]:
        # μ ± ε_k, ε_k ~ N(0, diag(σ²))
        return self.mirrored(rng, state.center, state.stdev, self.cfg.pop_size // 2), state

    def _tell(self, state: PGPEState, genomes: np.ndarray, cost: np.ndarray,
              rng: np.random.Generator, measures: np.ndarray | None = None) -> PGPEState:
        cfg = self.cfg
        self.check_told(genomes)
        n = genomes.shape[0] // 2
        u = centered_ranks(cost)
        grad_mu, grad_sigma = pgpe_gradients(u[:n], u[n:], half_differences(genomes),
                                             state.stdev)
        center, velocity = clipup_step(state.center, grad_mu, state.velocity,
                                       step_size=cfg.step_size, max_speed=cfg.max_speed,
                                       momentum=cfg.momentum)
        r = cfg.stdev_max_change
        stdev = np.clip(state.stdev + cfg.stdev_learning_rate * grad_sigma,
                        state.stdev * (1.0 - r), state.stdev * (1.0 + r))
        return replace(state, center=self.clip(center), stdev=stdev, velocity=velocity,
                       pop=np.array(genomes, dtype=float), cost=cost.copy())


def make_pgpe(genome: GenomeSpec, cfg: PGPEConfig, *, mutate: MutateFn | None = None) -> PGPE:
    """Factory for the ``ALGORITHMS`` registry (``"pgpe"``); ``mutate`` must be ``None``."""
    return PGPE(genome, cfg, mutate=mutate)
