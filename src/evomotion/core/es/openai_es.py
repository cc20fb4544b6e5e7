"""OpenAI-ES: Salimans, Ho, Chen, Sidor & Sutskever 2017, "Evolution Strategies as a
Scalable Alternative to Reinforcement Learning" (arXiv:1703.03864).

One generation (Algorithm 1 with the paper's refinements: mirrored sampling, fitness
shaping, weight decay, Adam):

1. ``ask``: ``N = pop_size / 2`` perturbations ``ε_k ~ N(0, I)`` drawn in one call;
   antithetic ("mirrored") sampling evaluates ``θ + σ ε_k`` (rows ``0..N-1``) and
   ``θ - σ ε_k`` (rows ``N..2N-1``), clipped into the genome bounds (see
   :mod:`~evomotion.core.es.common`).
2. ``tell``: fitness shaping by centred ranks over all ``2N`` costs (
   :func:`~evomotion.core.es.ranking.centered_ranks`: ``u`` in ``[-0.5, 0.5]``, larger for a
   lower cost), and the gradient estimate of Algorithm 1, step 5, with mirrored pairs:
   ``g = 1 / (2 N σ) Σ_k (u_k+ - u_k-) ε_k`` (``σ ε_k`` taken from the evaluated pair).
3. L2 weight decay (the paper's experiments): the loss gradient handed to Adam
   is ``-g + weight_decay θ``; Adam (Kingma & Ba 2015, :mod:`~evomotion.core.es.adam`)
   replaces the plain step ``θ += α g`` of Algorithm 1, step 5, as in the paper's experiments.

``σ`` (``sigma``) is fixed and in genome units, as in the paper. The centre starts at the
middle of the bounds or at row 0 of ``init``'s population; the first ``ask`` already
samples around it. ``center(state)`` is ``θ``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from evomotion.core.es.adam import adam_step
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
class OpenAIESConfig:
    """Settings of OpenAI-ES (``[algorithm]`` with ``name = "openai_es"``); the defaults are
    those of the paper's MuJoCo experiments (σ 0.02, Adam step 0.01, L2 0.005)."""

    name: str = "openai_es"
    pop_size: int = 100  # 2N: N mirrored pairs (even)
    sigma: float = 0.02  # noise std σ, genome units
    learning_rate: float = 0.01  # Adam's α
    weight_decay: float = 0.005  # L2 coefficient
    beta1: float = 0.9
    beta2: float = 0.999
    eps: float = 1e-8
    noise_table: int = 0  # > 0: perturbations from a shared table of this many N(0, 1) numbers

    def validate(self) -> None:
        check_pop_size(self, even=True)
        check_noise_table(self)
        check_positive(self, "sigma", "learning_rate", "eps")
        check_nonneg(self, "weight_decay")
        check_unit(self, "beta1", "beta2")


@dataclass
class OpenAIESState:
    center: np.ndarray  # θ [d]
    adam_m: np.ndarray  # Adam's first moment [d]
    adam_v: np.ndarray  # Adam's second raw moment [d]
    adam_t: int
    pop: np.ndarray  # the last told genomes [2N, d]
    cost: np.ndarray  # their costs
    best_x: np.ndarray
    best_cost: float
    generation: int = 0


class OpenAIES(GaussianES):
    """OpenAI-ES (Salimans et al. 2017): mirrored sampling, centred ranks, Adam, L2 decay."""

    name = "openai_es"
    cfg: OpenAIESConfig

    def init(self, rng: np.random.Generator,
             population: np.ndarray | None = None) -> OpenAIESState:
        c = self.start_center(population)
        n, d = self.cfg.pop_size, self.genome.dim
        return OpenAIESState(center=c, adam_m=np.zeros(d), adam_v=np.zeros(d), adam_t=0,
                             pop=np.repeat(c[None], n, axis=0), cost=np.full(n, np.inf),
                             best_x=c.copy(), best_cost=math.inf)

    def _ask(self, state: OpenAIESState,
             rng: np.random.Generator) -> tuple[np.ndarray, OpenAIESState]:
        # θ ± σ ε_k, ε_k ~ N(0, I)
        return self.mirrored(rng, state.center, self.cfg.sigma, self.cfg.pop_size // 2), state

    def _tell(self, state: OpenAIESState, genomes: np.ndarray, cost: np.ndarray,
              rng: np.random.Generator, measures: np.ndarray | None = None) -> OpenAIESState:
        cfg = self.cfg
        self.check_told(genomes)
        n = genomes.shape[0] // 2
        u = centered_ranks(cost)  # fitness shaping by centred ranks
        sigma_eps = half_differences(genomes)  # σ ε_k as evaluated
        # Alg. 1 step 5 with mirrored pairs: g = 1/(2Nσ) Σ (u+ - u-) ε_k
        g = ((u[:n] - u[n:]) @ sigma_eps) / (2 * n * cfg.sigma**2)
        loss_grad = -g + cfg.weight_decay * state.center  # L2 weight decay
        t = state.adam_t + 1
        center, m, v = adam_step(state.center, loss_grad, state.adam_m, state.adam_v, t,
                                 learning_rate=cfg.learning_rate, beta1=cfg.beta1,
                                 beta2=cfg.beta2, eps=cfg.eps)
        return replace(state, center=self.clip(center), adam_m=m, adam_v=v, adam_t=t,
                       pop=np.array(genomes, dtype=float), cost=cost.copy())


def make_openai_es(genome: GenomeSpec, cfg: OpenAIESConfig, *,
                   mutate: MutateFn | None = None) -> OpenAIES:
    """Factory for the ``ALGORITHMS`` registry (``"openai_es"``); ``mutate`` must be ``None``."""
    return OpenAIES(genome, cfg, mutate=mutate)
