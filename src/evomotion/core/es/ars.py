"""ARS: Mania, Guy & Recht 2018, "Simple random search provides a competitive approach to
reinforcement learning" (arXiv:1803.07055, NeurIPS 2018), Algorithm 2 (ARS V1, V1-t, V2,
V2-t).

One iteration ``j`` (paper's notation; rewards ``r = -cost``):

1. ``ask`` (Alg. 2, step 4): ``N = pop_size / 2`` directions ``δ_k ~ N(0, I)`` drawn in one
   call. Step 5: the mirrored policies ``M_j + ν δ_k`` (rows ``0..N-1``) and
   ``M_j - ν δ_k`` (rows ``N..2N-1``), clipped into the genome bounds (see
   :mod:`~evomotion.core.es.common`).
2. ``tell`` (Alg. 2, step 6): sort the directions by ``max(r_k+, r_k-)`` and keep the top
   ``b`` (``top_directions``; ``0`` means ``b = N``, which is ARS V1/V2). Ties keep the
   lower direction index first.
3. (Alg. 2, step 7) ``M_{j+1} = M_j + α / (b σ_R) Σ_{k=1..b} (r_(k)+ - r_(k)-) δ_(k)`` with
   ``σ_R`` the standard deviation of the ``2b`` rewards used (``ν δ_k`` is taken from the
   evaluated pair). With ``σ_R = 0`` the used rewards are all equal and the step is zero.

V1 and V2 differ only by the observation normalisation of step 5 (``diag(Σ_j)^(-1/2)
(x - μ_j)`` with running state statistics, step 8): that belongs to the *policy*, which sees
the states, not to this optimizer, which sees only parameters and rewards. ARS V2/V2-t is
this optimizer with a normalising policy (the problem keeps those statistics); V1/V1-t with
a plain one. The paper's "shift" (survival bonus removed during training) is likewise the
problem's.

Non-finite costs (failed rollouts) enter as the worst finite cost of the batch; when none
is finite the centre stays. ``M_0`` is the middle of the bounds, or row 0 of ``init``'s
population (the paper starts at 0). ``center(state)`` is ``M_j``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from evomotion.core.es.common import (
    GaussianES,
    check_noise_table,
    check_pop_size,
    check_positive,
    half_differences,
)
from evomotion.core.optimizer import MutateFn
from evomotion.core.problem import GenomeSpec
from evomotion.core.state import replaced as replace


@dataclass(frozen=True)
class ARSConfig:
    """Settings of ARS (``[algorithm]`` with ``name = "ars"``), named as in the paper."""

    name: str = "ars"
    pop_size: int = 16  # 2N rollouts per iteration (N directions, each evaluated ±)
    step_size: float = 0.02  # α
    noise_std: float = 0.03  # ν, genome units
    top_directions: int = 0  # b (the "-t" variants); 0 -> b = N (V1/V2)
    noise_table: int = 0  # > 0: perturbations from a shared table of this many N(0, 1) numbers

    @property
    def directions(self) -> int:
        """N, the number of directions: ``pop_size / 2``."""
        return self.pop_size // 2

    def validate(self) -> None:
        check_pop_size(self, even=True)
        check_noise_table(self)
        check_positive(self, "step_size", "noise_std")
        if not isinstance(self.top_directions, int) or \
                not 0 <= self.top_directions <= self.directions:
            raise ValueError(f"algorithm.top_directions must be in [0, N = pop_size / 2 = "
                             f"{self.directions}], got {self.top_directions}")


@dataclass
class ARSState:
    center: np.ndarray  # M_j [d]
    pop: np.ndarray  # the last told genomes [2N, d]
    cost: np.ndarray  # their costs
    best_x: np.ndarray
    best_cost: float
    generation: int = 0


def top_directions(r_plus: np.ndarray, r_minus: np.ndarray, b: int) -> np.ndarray:
    """Indices of the ``b`` directions with the largest ``max(r+, r-)`` (Alg. 2, step 6),
    best first; ties keep the lower index first."""
    return np.argsort(-np.maximum(r_plus, r_minus), kind="stable")[:b]


def ars_step(r_plus: np.ndarray, r_minus: np.ndarray, nu_delta: np.ndarray, b: int, *,
             step_size: float, noise_std: float) -> np.ndarray:
    """The change of ``M`` (Alg. 2, steps 6-7) from the rewards of the mirrored pairs and
    their perturbations ``ν δ_k`` (rows)."""
    top = top_directions(r_plus, r_minus, b)
    used = np.concatenate((r_plus[top], r_minus[top]))
    sigma_r = float(np.std(used))
    if not sigma_r > 0.0:
        return np.zeros(nu_delta.shape[1])
    step: np.ndarray = ((r_plus[top] - r_minus[top]) @ nu_delta[top]) * (
        step_size / (b * sigma_r * noise_std))
    return step


class ARS(GaussianES):
    """Augmented Random Search (Mania et al. 2018), V1/V2 and their top-``b`` variants."""

    name = "ars"
    cfg: ARSConfig

    def init(self, rng: np.random.Generator, population: np.ndarray | None = None) -> ARSState:
        c = self.start_center(population)
        n = self.cfg.pop_size
        return ARSState(center=c, pop=np.repeat(c[None], n, axis=0), cost=np.full(n, np.inf),
                        best_x=c.copy(), best_cost=math.inf)

    def _ask(self, state: ARSState, rng: np.random.Generator) -> tuple[np.ndarray, ARSState]:
        # steps 4-5: M_j ± ν δ_k, δ_k ~ N(0, I)
        return self.mirrored(rng, state.center, self.cfg.noise_std, self.cfg.directions), state

    def _tell(self, state: ARSState, genomes: np.ndarray, cost: np.ndarray,
              rng: np.random.Generator, measures: np.ndarray | None = None) -> ARSState:
        cfg = self.cfg
        self.check_told(genomes)
        new = replace(state, pop=np.array(genomes, dtype=float), cost=cost.copy())
        finite = np.isfinite(cost)
        if not finite.any():
            return new
        reward = -np.where(finite, cost, cost[finite].max())
        n = cfg.directions
        step = ars_step(reward[:n], reward[n:], half_differences(genomes),
                        cfg.top_directions or n, step_size=cfg.step_size,
                        noise_std=cfg.noise_std)
        return replace(new, center=self.clip(state.center + step))  # step 7


def make_ars(genome: GenomeSpec, cfg: ARSConfig, *, mutate: MutateFn | None = None) -> ARS:
    """Factory for the ``ALGORITHMS`` registry (``"ars"``); ``mutate`` must be ``None``."""
    return ARS(genome, cfg, mutate=mutate)
