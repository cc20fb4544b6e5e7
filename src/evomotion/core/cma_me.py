"""CMA-ME with improvement-ranking emitters, and CMA-MAE's threshold archive.

Sources: M. C. Fontaine, J. Togelius, S. Nikolaidis and A. K. Hoover, "Covariance Matrix
Adaptation for the Rapid Illumination of Behavior Space", GECCO 2020, section 4 (improvement
emitters): ``emitters`` CMA-ES instances share one archive; each ranks its ``pop_size``
offspring by what they did to the archive, new cells first (by objective), then improved
elites (by the gain ``f - f_elite``), then the rest (by the same gain), updates its
distribution from that ranking (the CMA-ES update of Hansen's tutorial, arXiv:1604.00772,
eqs. 41-47, :mod:`evomotion.core.cmaes_update`), and restarts from a uniformly chosen elite
with ``sigma0`` and ``C = I`` when none of its offspring changed the archive or its
distribution has collapsed. M. C. Fontaine and S. Nikolaidis, "Covariance Matrix Adaptation
MAP-Annealing", GECCO 2023, Alg. 1: with ``learning_rate`` alpha < 1 the archive accepts
``f > t_e`` and anneals the threshold ``t_e <- (1 - alpha) t_e + alpha f`` (eq. 2, empty cells
start at ``threshold_min``); the gain is ``f - t_e``, ranked without the status stage, and
emitters restart only on convergence; an elitist *result archive* beside it keeps the best
elite of each cell, which is what statistics and runs hand over. ``learning_rate = 1`` is
CMA-ME.

Selection: ``"filter"`` (CMA-ME's): the parents are the offspring that changed the archive,
with log-decreasing weights and the learning rates of that ``mu``; ``"mu"`` (CMA-MAE's
released configuration): the standard weights over the whole ranking (mu = lambda / 2,
active negative weights). Genomes live in the
normalised box [0, 1]^d, ``sigma0`` is a fraction of each gene's range, and samples outside
the box are clipped and treated as injected (Hansen 2011), as in :mod:`.cmaes`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from evomotion.core.archives import NOT_ADDED, ArchiveState, add
from evomotion.core.checks import check_choice, check_fields, check_number, inf_ok
from evomotion.core.cmaes_params import strategy_params
from evomotion.core.cmaes_update import (
    clip_injected,
    update_covariance,
    update_eigensystem,
    update_evolution_paths,
    update_mean,
    update_step_size,
)
from evomotion.core.optimizer import MutateFn
from evomotion.core.problem import GenomeSpec, MeasureSpec
from evomotion.core.qd import ArchiveConfig, QDOptimizer, as_measures
from evomotion.core.state import replaced

MAX_EMITTERS = 10_000


@dataclass(frozen=True)
class CMAMEConfig(ArchiveConfig):
    """Settings of CMA-ME / CMA-MAE (``[algorithm]`` with ``name = "cma_me"``)."""

    name: str = "cma_me"
    emitters: int = 5
    pop_size: int = 30  # lambda of each emitter (pyribs: batch_size)
    sigma0: float = 0.1  # initial step size, fraction of each gene's range
    x0: str = "initial"  # initial: the problem's initial population mean (else the centre)
    ranking: str = "2imp"  # 2imp: status, then gain (CMA-ME) | imp: gain only (CMA-MAE)
    selection: str = "filter"  # filter: parents = the offspring that changed the archive | mu
    restart_rule: str = "no_improvement"  # no_improvement (CMA-ME) | basic: convergence only
    learning_rate: float = 1.0  # alpha: 1 = CMA-ME (elitist); < 1 = CMA-MAE thresholds
    #: CMA-MAE: threshold of an empty cell (finite when learning_rate < 1)
    threshold_min: float = inf_ok(-math.inf, "no threshold: the elitist archive of CMA-ME")

    needs_measures = True  # class attribute, not a setting

    def validate(self) -> None:
        check_fields(self, "algorithm")
        check_number("algorithm.emitters", self.emitters, lo=1, hi=MAX_EMITTERS, integer=True)
        check_number("algorithm.pop_size", self.pop_size, lo=2, hi=10**7, integer=True)
        check_number("algorithm.sigma0", self.sigma0, lo=0.0, lo_open=True)
        check_choice("algorithm.x0", self.x0, ("initial", "center"))
        check_choice("algorithm.ranking", self.ranking, ("2imp", "imp"))
        check_choice("algorithm.selection", self.selection, ("filter", "mu"))
        check_choice("algorithm.restart_rule", self.restart_rule, ("no_improvement", "basic"))
        check_number("algorithm.learning_rate", self.learning_rate, lo=0.0, hi=1.0)
        check_number("algorithm.threshold_min", self.threshold_min, allow_inf=True)
        if self.learning_rate < 1.0 and not math.isfinite(self.threshold_min):
            raise ValueError("algorithm.threshold_min must be finite when "
                             f"algorithm.learning_rate < 1 (CMA-MAE), got {self.threshold_min}")
        self.validate_archive()


@dataclass
class CMAMEState:
    """The archive(s) and the emitters' distributions, stacked ``[emitters, ...]``."""

    archive: ArchiveState  # drives the emitters (thresholded when learning_rate < 1)
    result: ArchiveState  # elitist; the same object's arrays as archive when alpha = 1
    mean: np.ndarray  # [E, d] normalised
    sigma: np.ndarray  # [E]
    C: np.ndarray  # [E, d, d]
    B: np.ndarray
    D: np.ndarray  # [E, d]
    p_sigma: np.ndarray
    p_c: np.ndarray
    emitter_generation: np.ndarray  # [E] generations since the emitter's last restart
    eigen_generation: np.ndarray  # [E]
    restarts: np.ndarray  # [E]
    pop: np.ndarray  # the last asked batch [E * lambda, d]
    modified: np.ndarray  # bool[E * lambda]: clipped into the box
    cost: np.ndarray
    best_x: np.ndarray
    best_cost: float
    generation: int = 0
    evaluations: int = 0


class CMAME(QDOptimizer):
    """CMA-ME (Fontaine et al. 2020) / CMA-MAE (Fontaine & Nikolaidis 2023)."""

    name = "cma_me"

    def __init__(self, genome: GenomeSpec, cfg: CMAMEConfig | None = None, *,
                 measures: MeasureSpec | None = None) -> None:
        cfg = cfg or CMAMEConfig()
        cfg.validate()
        super().__init__(genome, cfg, measures)
        self.n = genome.dim
        self.fixed = genome.span <= 0

    def to_unit(self, x: np.ndarray) -> np.ndarray:
        return (x - self.genome.lower) / self.span

    def to_genome(self, u: np.ndarray) -> np.ndarray:
        return self.genome.lower + self.span * u

    def init(self, rng: np.random.Generator,
             population: np.ndarray | None = None) -> CMAMEState:
        cfg, n, E = self.cfg, self.n, self.cfg.emitters
        x0 = np.full(n, 0.5)
        if population is not None:
            p = np.asarray(population, dtype=float)
            if p.ndim != 2 or p.shape[0] < 1 or p.shape[1] != n:
                raise ValueError(f"cma_me: initial population has shape {p.shape}, "
                                 f"want (k, {n})")
            if cfg.x0 == "initial":
                x0 = np.clip(self.to_unit(p.mean(axis=0)), 0.0, 1.0)
        x0[self.fixed] = 0.0
        archive = self.spec.init(rng, n, cfg.threshold_min if cfg.learning_rate < 1 else -np.inf)
        result = archive if cfg.learning_rate >= 1 else \
            replaced(archive, threshold=np.full(self.spec.cells, -np.inf))  # same cells
        eye = np.broadcast_to(np.eye(n), (E, n, n)).copy()
        lam = cfg.emitters * cfg.pop_size
        return CMAMEState(archive, result, np.tile(x0, (E, 1)), np.full(E, cfg.sigma0),
                          eye, eye.copy(), np.ones((E, n)), np.zeros((E, n)), np.zeros((E, n)),
                          np.zeros(E, np.int64), np.zeros(E, np.int64), np.zeros(E, np.int64),
                          np.zeros((lam, n)), np.zeros(lam, bool), np.full(lam, math.inf),
                          self.to_genome(x0), math.inf)

    def _ask(self, state: CMAMEState, rng: np.random.Generator):
        E, lam, n = self.cfg.emitters, self.cfg.pop_size, self.n
        z = rng.standard_normal((E, lam, n))
        u = state.mean[:, None, :] + state.sigma[:, None, None] * np.einsum(
            "eij,ekj->eki", state.B, z * state.D[:, None, :])  # eqs. 38-40, per emitter
        u = u.reshape(E * lam, n)
        clipped = np.clip(u, 0.0, 1.0)
        modified = np.any(clipped != u, axis=1)
        clipped[:, self.fixed] = 0.0
        x = self.to_genome(clipped)
        return x, replaced(state, pop=x, modified=modified, cost=np.full(E * lam, math.inf))

    def _tell(self, s: CMAMEState, genomes: np.ndarray, cost: np.ndarray,
              rng: np.random.Generator, measures: np.ndarray | None = None) -> CMAMEState:
        cfg, E, lam = self.cfg, self.cfg.emitters, self.cfg.pop_size
        if genomes.shape[0] != E * lam:
            raise ValueError(f"cma_me: tell got {genomes.shape[0]} genomes, asked {E * lam}")
        m = as_measures(measures, len(genomes), self.spec.measure_dim)
        obj = -cost
        archive, status, value = add(self.spec, s.archive, genomes, obj, m, cfg.learning_rate)
        result = archive
        if cfg.learning_rate < 1:
            result, _, _ = add(self.spec, s.result, genomes, obj, m)
        fields = {k: getattr(s, k).copy() for k in ("mean", "sigma", "C", "B", "D", "p_sigma",
                                                     "p_c", "emitter_generation",
                                                     "eigen_generation", "restarts")}
        p_mu = strategy_params(self.n, lam)
        for e in range(E):
            rows = slice(e * lam, (e + 1) * lam)
            st, val = status[rows], value[rows]
            key = (-val,) if cfg.ranking == "imp" else (-val, -st)
            order = np.lexsort(key)  # last key first: status, then gain
            p = p_mu if cfg.selection == "mu" else filter_params(self.n, lam,
                                                                  int((st > 0).sum()))
            if p is not None:
                self._update(fields, e, p, genomes[rows][order], s.modified[rows][order],
                             s.pop[rows][order])
            stalled = cfg.restart_rule == "no_improvement" and np.all(st == NOT_ADDED)
            if (stalled or self._converged(fields, e)) and archive.occupied.any():
                self._restart(fields, e, archive, rng)
        return replaced(s, archive=archive, result=result, cost=cost.copy(),
                        evaluations=s.evaluations + len(genomes), **fields)

    def _update(self, f: dict, e: int, p, x_sorted: np.ndarray, modified: np.ndarray,
                asked: np.ndarray) -> None:
        """One CMA-ES update of emitter ``e`` from its offspring in ranking order."""
        mean, sigma, B, D = f["mean"][e], float(f["sigma"][e]), f["B"][e], f["D"][e]
        changed = modified | np.any(x_sorted != asked, axis=1)
        y = (self.to_unit(x_sorted) - mean) / sigma
        y[:, self.fixed] = 0.0
        y, z, znorm = clip_injected(y, changed, B, D)
        gen = int(f["emitter_generation"][e]) + 1
        new_mean, y_w = update_mean(p, mean, sigma, y)  # eqs. 41-42
        p_sigma, p_c, h_sigma = update_evolution_paths(p, f["p_sigma"][e], f["p_c"][e], z,
                                                       y_w, gen)  # eqs. 43-45
        C = update_covariance(p, f["C"][e], p_c, h_sigma, y, znorm, changed)  # eqs. 46-47
        ranks = np.arange(len(y), dtype=float)  # distinct: no flat-fitness rescue on ranks
        f["sigma"][e] = update_step_size(p, sigma, p_sigma, ranks)  # eq. 44
        f["mean"][e], f["p_sigma"][e], f["p_c"][e], f["C"][e] = new_mean, p_sigma, p_c, C
        f["emitter_generation"][e] = gen
        if gen - int(f["eigen_generation"][e]) >= p.eigen_every:
            f["C"][e], f["B"][e], f["D"][e] = update_eigensystem(C)
            f["eigen_generation"][e] = gen

    def _converged(self, f: dict, e: int) -> bool:
        """The distribution has collapsed (every axis below 1e-12 of the range) or ``C`` is
        ill-conditioned (condition number above 1e14)."""
        D = f["D"][e]
        return bool(f["sigma"][e] * D.max() < 1e-12 or (D.max() / max(D.min(), 1e-300)) ** 2
                    > 1e14 or not np.isfinite(f["sigma"][e]))

    def _restart(self, f: dict, e: int, archive: ArchiveState, rng: np.random.Generator) -> None:
        n = self.n
        x = self.random_elites(archive, rng, 1)[0]
        f["mean"][e] = np.where(self.fixed, 0.0, self.to_unit(x))
        f["sigma"][e] = self.cfg.sigma0
        f["C"][e], f["B"][e], f["D"][e] = np.eye(n), np.eye(n), np.ones(n)
        f["p_sigma"][e], f["p_c"][e] = np.zeros(n), np.zeros(n)
        f["emitter_generation"][e] = f["eigen_generation"][e] = 0
        f["restarts"][e] += 1

    def result_archive(self, state: CMAMEState) -> ArchiveState:
        return state.result


def filter_params(n: int, lam: int, added: int):
    """Strategy parameters whose parents are the ``added`` best-ranked offspring, with the
    log-decreasing positive weights and the learning rates of ``mu = added`` (Hansen's Table 1
    for that ``mu_eff``), no negative weights; ``None`` when nothing was added (no update:
    the emitter restarts)."""
    if added < 1:
        return None
    base = strategy_params(n, max(2 * added, 2))
    w = np.zeros(lam)
    w[:added] = base.weights[:added]
    return dataclasses.replace(base, lam=lam, mu=added, weights=w)


def make_cma_me(genome: GenomeSpec, cfg: CMAMEConfig, *, mutate: MutateFn | None = None,
                measures: MeasureSpec | None = None) -> CMAME:
    """Factory for the ``ALGORITHMS`` registry (``"cma_me"``); ``mutate`` must be ``None``."""
    if mutate is not None:
        raise ValueError("cma_me: CMA-ES emitters have no mutation operator to replace; a "
                         "mutate hook is not supported")
    return CMAME(genome, cfg, measures=measures)
