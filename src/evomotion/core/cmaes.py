"""CMA-ES with IPOP/BIPOP restarts, box bounds and the Tent/Lévy improvements of paper 002.

Sources:
- N. Hansen, "The CMA Evolution Strategy: A Tutorial", arXiv:1604.00772 (2016/2023): sampling,
  weights incl. negative (active) weights, all learning rates, the update of m, p_sigma, sigma,
  p_c, C (tutorial Fig. 6 / Table 1) and the termination criteria of its appendix B.3.
- N. Hansen, "Injecting External Solutions Into CMA-ES", arXiv:1110.4181 (2011): candidates not
  drawn from N(m, sigma^2 C) enter the update with their Mahalanobis step length clipped to
  ``c_y = sqrt(n) + 2 n / (n + 2)`` (the value pycma uses for injected solutions).
- A. Auger & N. Hansen, "A Restart CMA Evolution Strategy With Increasing Population Size",
  CEC 2005 (IPOP); N. Hansen, "Benchmarking a BI-Population CMA-ES on the BBOB-2009 Function
  Testbed", GECCO 2009 (BIPOP).
- Paper 002 (Zhou & Liang 2023), sections 2.2-2.3: Tent-map mean perturbation and Lévy flights.

Everything runs in normalised coordinates ``u = (x - lower) / span`` so that ``sigma0`` is a
fraction of each gene's range. How the options enter one generation:

1. ``ask``: ``z ~ N(0, I)``, ``u_i = m + sigma B D z_i``.  *Lévy* (if ``levy``): a random
   ``round(levy_fraction * lambda)`` of the candidates get ``u_i += alpha sigma B (D (.) s_i)``
   with ``s_i`` a vector of Mantegna steps: paper 002's ``x' = x + alpha (.) Levy(beta)``, taken
   element-wise in the eigenbasis of C so that the jump respects the learned shape (a jump
   along the genome axes degraded CMA-ES on Rosenbrock in our tests).  *Bounds*
   (``bound_handling="reinject"``): candidates are clipped into the box. Every candidate changed
   by Lévy or clipping is flagged ``modified``.
2. ``tell``: ``y_i = (u_i - m) / sigma`` from the genomes actually evaluated. For modified rows
   (or rows the caller changed) ``y_i <- y_i min(1, c_y / ||C^{-1/2} y_i||)`` (injection), so an
   off-distribution candidate can pull the mean and the covariance at most as far as a typical
   sample would. Modified rows never receive a negative (active) weight: the active update
   assumes samples of the current distribution. Otherwise the tutorial's update of m,
   p_sigma, sigma, p_c and C follows unchanged.
3. *Tent* (if ``chaos``): after the update, when the best cost since the last jump (or
   restart) has not improved for ``chaos_patience`` generations (default ``10 + ceil(30 n /
   lambda)``, the tutorial's tolfun window), the chaos state is iterated, mapped into the box
   (``c = L + (U - L) x``, see :mod:`evomotion.core.chaos`) and the mean moves by
   ``Delta m = chaos_strength (c - m)``. The jump is not a selected step, so the evolution
   paths are reset and it never enters p_sigma, p_c or C; sigma becomes
   ``max(sigma, rms(Delta m))`` so that the new region is searched at the jump's scale, and
   the stagnation histories restart. At most ``chaos_max_jumps`` jumps per restart, after
   which the ordinary termination criteria (and IPOP/BIPOP) take over.
4. Termination of a run (tolfun, tolx, noeffectaxis, noeffectcoord, conditioncov,
   tolstagnation, maxiter) triggers a restart (IPOP: lambda *= inc_popsize; BIPOP: alternates
   large and small populations by evaluations spent) until ``max_restarts``; the reasons are
   kept in ``state.stop_log`` and the final one in ``state.stop_reason``.

Modules: the strategy parameters are in :mod:`~evomotion.core.cmaes_params` (Table 1), the
update steps in :mod:`~evomotion.core.cmaes_update` (one function per tutorial equation), the
termination criteria in :mod:`~evomotion.core.cmaes_stop`, IPOP/BIPOP in
:mod:`~evomotion.core.cmaes_restarts`, the Lévy and Tent options in
:mod:`~evomotion.core.cmaes_levy_tent`; this module holds the config, the state and the ask/tell
that chain them. State is replaced, never mutated. ``state.generation`` counts every
generation (all restarts); ``state.restart_generation`` is the tutorial's ``g`` within the
current run (reset by a restart or a Tent jump).

``init(rng, population)``: the mean starts at the mean of the given ``[k, d]`` genomes
(normalised; fixed genes 0) instead of ``x0``; the random stream is the same as without it.
CMA-ES has no mutation operator: a ``mutate`` hook raises ``ValueError``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from evomotion.core.chaos import validate_tent
from evomotion.core.checks import MAX_POP_SIZE, check_fields, check_number
from evomotion.core.cmaes_levy_tent import chaos_due, chaos_jump, levy_candidates, tent_start
from evomotion.core.cmaes_params import StrategyParams, strategy_params
from evomotion.core.cmaes_restarts import fresh_distribution, initial_lambda, restart
from evomotion.core.cmaes_stop import push_history, stop_reason
from evomotion.core.cmaes_update import (
    clip_injected,
    sample,
    update_covariance,
    update_eigensystem,
    update_evolution_paths,
    update_mean,
    update_step_size,
)
from evomotion.core.levy import mantegna_sigma_u
from evomotion.core.optimizer import MutateFn, Optimizer
from evomotion.core.problem import GenomeSpec
from evomotion.errors import InputError


@dataclass(frozen=True)
class CMAESConfig:
    """Settings of CMA-ES (``[algorithm]`` with ``name = "cmaes"``)."""

    name: str = "cmaes"
    pop_size: int = 0  # lambda; 0 -> 4 + floor(3 ln n)
    sigma0: float = 0.3  # initial step size as a fraction of each gene's range
    x0: str = "uniform"  # "uniform" (random in the box) or "center"
    bound_handling: str = "reinject"  # "reinject" (clip + injection) or "none"
    restarts: str = "ipop"  # "none", "ipop" or "bipop"
    max_restarts: int = 9
    inc_popsize: float = 2.0
    tolfun: float = 1e-11
    tolx: float = 1e-12  # in normalised units (fraction of the range)
    chaos: bool = False
    chaos_mu: float = 1.5
    chaos_strength: float = 0.3
    chaos_patience: int = 0  # generations without improvement; 0 -> 10 + ceil(30 n / lambda)
    chaos_max_jumps: int = 3  # per restart, so that IPOP/BIPOP restarts still happen
    levy: bool = False
    levy_beta: float = 1.5
    levy_alpha: float = 1.0
    levy_fraction: float = 0.2

    def validate(self) -> None:
        check_fields(self, "algorithm")
        if self.pop_size != 0 and self.pop_size < 2:
            raise ValueError(f"algorithm.pop_size must be 0 (default) or >= 2, got {self.pop_size}")
        check_number("algorithm.pop_size", self.pop_size, hi=MAX_POP_SIZE, integer=True)
        if self.sigma0 <= 0:
            raise ValueError(f"algorithm.sigma0 must be > 0, got {self.sigma0}")
        for key in ("max_restarts", "chaos_patience", "chaos_max_jumps"):
            check_number(f"algorithm.{key}", getattr(self, key), lo=0, integer=True)
        for key in ("tolfun", "tolx"):
            check_number(f"algorithm.{key}", getattr(self, key), lo=0.0)
        choices = {"x0": ("uniform", "center"), "bound_handling": ("reinject", "none"),
                   "restarts": ("none", "ipop", "bipop")}
        for key, allowed in choices.items():
            if getattr(self, key) not in allowed:
                raise ValueError(f"algorithm.{key} must be one of {allowed}, got "
                                 f"{getattr(self, key)!r}")
        if self.inc_popsize <= 1:
            raise ValueError(f"algorithm.inc_popsize must be > 1, got {self.inc_popsize}")
        lam0 = self.pop_size or 4  # the smallest default lambda
        if self.restarts != "none" and (math.log(lam0) + self.max_restarts
                                        * math.log(self.inc_popsize)) > math.log(MAX_POP_SIZE):
            raise InputError(f"algorithm.inc_popsize={self.inc_popsize}, algorithm.max_restarts="
                             f"{self.max_restarts}: the last restart's population would exceed "
                             f"{MAX_POP_SIZE}")
        # the Tent and Levy settings are checked even when their option is off
        try:
            validate_tent(self.chaos_mu, 0.3)
            mantegna_sigma_u(self.levy_beta)
        except ValueError as e:
            key = "chaos_mu" if "Tent" in str(e) else "levy_beta"
            raise InputError(f"algorithm.{key}: {e}") from None
        if not 0 < self.chaos_strength <= 1 or self.chaos_patience < 0:
            raise ValueError("algorithm.chaos_strength must be in (0, 1] and "
                             "algorithm.chaos_patience >= 0")
        if self.levy_alpha <= 0 or not 0 < self.levy_fraction <= 1:
            raise ValueError("algorithm.levy_alpha must be > 0 and "
                             "algorithm.levy_fraction in (0, 1]")


@dataclass
class CMAESState:
    """Everything that changes; arrays and scalars only (checkpointable)."""

    mean: np.ndarray  # m, normalised [d]
    sigma: float
    C: np.ndarray  # [d, d]
    B: np.ndarray  # eigenvectors of C (columns)
    D: np.ndarray  # sqrt of eigenvalues
    p_sigma: np.ndarray
    p_c: np.ndarray
    lam: int
    pop: np.ndarray  # last asked genomes (problem units) [lam, d]
    cost: np.ndarray  # their costs (inf before tell)
    modified: np.ndarray  # bool[lam]: Lévy-moved or bound-repaired (treated as injected)
    best_x: np.ndarray
    best_cost: float
    tent_x: np.ndarray  # chaos state per dimension
    best_hist: np.ndarray  # best cost per generation of this run
    median_hist: np.ndarray
    generation: int = 0  # completed generations, all restarts
    restart_generation: int = 0  # g: generations since the last restart or Tent jump
    evaluations: int = 0
    eigen_generation: int = 0  # restart_generation of the last eigendecomposition
    restarts: int = 0
    restart_best: float = math.inf
    since_improvement: int = 0
    chaos_jumps: int = 0
    restart_jumps: int = 0
    levy_moves: int = 0
    regime: str = "large"
    large_restarts: int = 0
    evals_large: int = 0
    evals_small: int = 0
    restart_evals0: int = 0
    stop_reason: str = ""
    stop_log: str = ""
    done: bool = False


class CMAES(Optimizer):
    """CMA-ES (Hansen 2016) with optional Tent-map and Lévy-flight improvements (paper 002)."""

    name = "cmaes"

    def __init__(self, genome: GenomeSpec, cfg: CMAESConfig | None = None, *,
                 mutate: MutateFn | None = None) -> None:
        if mutate is not None:
            raise ValueError("cmaes: CMA-ES has no mutation operator to replace; "
                             "a mutate hook is not supported")
        super().__init__(genome)
        self.cfg = cfg or CMAESConfig()
        self.cfg.validate()
        self.n = genome.dim
        self.span = np.where(genome.span > 0, genome.span, 1.0)
        self.fixed = genome.span <= 0
        self.lam0 = initial_lambda(self.cfg, self.n)

    def expected_population(self) -> int | None:
        """Rows of the population: lambda (the default ``4 + floor(3 ln n)`` when
        ``pop_size`` is 0), or ``None`` with restarts, which change lambda."""
        return self.lam0 if self.cfg.restarts == "none" else None

    def params(self, lam: int) -> StrategyParams:
        return strategy_params(self.n, lam)

    def to_genome(self, u: np.ndarray) -> np.ndarray:
        return self.genome.lower + self.span * u

    def to_unit(self, x: np.ndarray) -> np.ndarray:
        return (x - self.genome.lower) / self.span

    def init(self, rng: np.random.Generator,
             population: np.ndarray | None = None) -> CMAESState:
        n, lam = self.n, self.lam0
        tent0 = tent_start(self.cfg, rng, n)
        fresh = fresh_distribution(self.cfg, self.fixed, rng, lam, self.cfg.sigma0)
        if population is not None:
            x = np.asarray(population, dtype=float)
            if x.ndim != 2 or x.shape[0] < 1 or x.shape[1] != n:
                raise ValueError(f"cmaes: initial population has shape {x.shape}, "
                                 f"want (k, {n})")
            fresh["mean"] = np.where(self.fixed, 0.0, self.to_unit(x.mean(axis=0)))
        return CMAESState(**fresh, pop=np.zeros((lam, n)), cost=np.full(lam, np.inf),
                          modified=np.zeros(lam, bool),
                          best_x=self.to_genome(np.full(n, 0.5)), best_cost=math.inf,
                          tent_x=tent0)

    def _ask(self, state: CMAESState, rng: np.random.Generator) -> tuple[np.ndarray, CMAESState]:
        cfg, lam = self.cfg, state.lam
        u = sample(rng, lam, state.mean, state.sigma, state.B, state.D)  # eqs. 38-40
        modified = np.zeros(lam, bool)
        levy_moves = state.levy_moves
        if cfg.levy:
            u, rows = levy_candidates(cfg, state, u, rng)
            modified[rows] = True
            levy_moves += len(rows)
        if cfg.bound_handling == "reinject":
            clipped = np.clip(u, 0.0, 1.0)
            modified |= np.any(clipped != u, axis=1)
            u = clipped
        u[:, self.fixed] = 0.0
        pop = self.to_genome(u)
        return pop, replace(state, pop=pop, cost=np.full(lam, np.inf), modified=modified,
                            levy_moves=levy_moves)

    def _tell(self, s: CMAESState, genomes: np.ndarray, cost: np.ndarray,
              rng: np.random.Generator, measures: np.ndarray | None = None) -> CMAESState:
        """One generation: selection, the tutorial's update of m, p_sigma, p_c, C, sigma,
        then termination (and restart) or a Tent jump."""
        if genomes.shape[0] != s.lam:
            raise ValueError(f"cmaes: tell got {genomes.shape[0]} genomes, asked {s.lam}")
        p, cfg = strategy_params(self.n, s.lam), self.cfg
        order = np.argsort(cost, kind="stable")
        costs_sorted = cost[order]
        improved = costs_sorted[0] < s.restart_best
        s = replace(s, cost=cost.copy(), evaluations=s.evaluations + s.lam,
                    restart_best=float(costs_sorted[0]) if improved else s.restart_best,
                    since_improvement=0 if improved else s.since_improvement + 1)
        # steps y_{i:lambda} of the evaluated genomes; injected ones clipped (Hansen 2011)
        changed = (s.modified | np.any(genomes != s.pop, axis=1))[order]
        y = (self.to_unit(genomes[order]) - s.mean) / s.sigma
        y[:, self.fixed] = 0.0
        y, z, znorm = clip_injected(y, changed, s.B, s.D)
        gen = s.restart_generation + 1
        mean, y_w = update_mean(p, s.mean, s.sigma, y)  # eqs. 41-42
        p_sigma, p_c, h_sigma = update_evolution_paths(p, s.p_sigma, s.p_c, z, y_w, gen)
        C = update_covariance(p, s.C, p_c, h_sigma, y, znorm, changed)  # eqs. 46-47
        sigma = update_step_size(p, s.sigma, p_sigma, costs_sorted)  # eq. 44
        s = replace(s, mean=mean, sigma=sigma, C=C, p_sigma=p_sigma, p_c=p_c,
                    restart_generation=gen,
                    best_hist=push_history(s.best_hist, costs_sorted[0]),
                    median_hist=push_history(s.median_hist, float(np.median(costs_sorted))))
        if gen - s.eigen_generation >= p.eigen_every:
            C, B, D = update_eigensystem(s.C)
            s = replace(s, C=C, B=B, D=D, eigen_generation=gen)
        reason = stop_reason(cfg, s, costs_sorted)
        if reason:
            return restart(cfg, self.fixed, s, reason, rng)
        if chaos_due(cfg, s):
            s = chaos_jump(cfg, self.fixed, s)
        return s

    def stop(self, state: CMAESState) -> str | None:
        """Why the search ended (``None`` while restarts or the run continue)."""
        return state.stop_reason if state.done else None


def make_cmaes(genome: GenomeSpec, cfg: CMAESConfig, *,
               mutate: MutateFn | None = None) -> CMAES:
    """Factory for the ``ALGORITHMS`` registry (``"cmaes"``); ``mutate`` must be ``None``."""
    return CMAES(genome, cfg, mutate=mutate)
