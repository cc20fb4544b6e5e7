"""Seed 001's schedule (section 2): N arm generations, then M finger generations, then
whole-limb generations until a solution is found or the budget (generations, wall time) ends.

In the arm phase the objective is the wrist's distance to the nearest wrist-candidate cell
and only arm bones count as intersections; in the finger and whole-limb phases it is the sum
of matched tip-target distances and every bone counts (section 3.3). A solution: every tip
within ``tolerance * diagonal`` of a distinct target, no intersection, all limits respected.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from evomotion.studies.arm_ik.evolution import crossover, mutate, parents, rank_order, survivors
from evomotion.studies.arm_ik.problem import ArmIKConfig, ArmIKProblem, Assessment

STATS_COLUMNS = (
    "generation", "phase", "evaluations", "time_s", "best_objective", "best_intersections",
    "best_feasible_objective", "mean_objective", "var_objective", "mean_intersections",
    "var_intersections", "originality", "feasible_fraction", "best_limb_distance",
    "best_limb_intersections", "best_limb_max_tip_error", "solved", "restarts",
)


def phase_objective(a: Assessment, mode: str) -> tuple[np.ndarray, np.ndarray]:
    """(objective, intersections) that rank individuals in phase ``mode``."""
    if mode == "arm":
        return a.wrist_distance, a.arm_intersections
    return a.distance, a.intersections


@dataclass
class RunResult:
    """Outcome of one schedule run; ``best`` is the best whole limb (first solution if any)."""

    problem: ArmIKProblem
    best: np.ndarray
    best_assessment: Assessment
    solved: bool
    time_to_solution_s: float | None
    generations: int
    evaluations: int
    elapsed_s: float
    history: np.ndarray  # (generations + 1, dim): best whole limb after each generation
    stats: list[dict] = field(default_factory=list)
    restarts: int = 0
    final_population: np.ndarray | None = None
    final_distance: np.ndarray | None = None  # whole-limb objective of the final population
    time_to_solution_cpu_s: float | None = None  # process CPU time (robust on a busy machine)


def _limb_key(a: Assessment) -> np.ndarray:
    return rank_order(a.intersections, a.distance)


class _Run:
    """Mutable state of one schedule run (population, best limb, counters)."""

    def __init__(self, cfg: ArmIKConfig, prob: ArmIKProblem, seed: int, t0: float) -> None:
        self.cfg, self.prob, self.t0 = cfg, prob, t0
        self.c0 = time.process_time()
        self.solved_cpu: float | None = None
        self.rng = np.random.default_rng(seed)
        self.gen = self.evals = self.restarts = 0
        self.solved_at: float | None = None
        self.stats: list[dict] = []
        self.fresh_population()
        i = int(np.argmin(_limb_key(self.A)))
        self.best, self.best_a = self.pop[i].copy(), self.A.take(np.array([i]))
        self.history = [self.best.copy()]
        self.note_solution()

    def fresh_population(self) -> None:
        self.pop = self.prob.genome.sample(self.rng, self.cfg.pop_size)
        self.A = self.prob.assess(self.pop)
        self.evals += self.cfg.pop_size

    def note_solution(self) -> None:
        if self.best_a.solved[0] and self.solved_at is None:
            self.solved_at = time.perf_counter() - self.t0
            self.solved_cpu = time.process_time() - self.c0

    @property
    def done(self) -> bool:
        out_of_time = time.perf_counter() - self.t0 > self.cfg.wall_seconds
        return out_of_time or (self.solved_at is not None and self.cfg.stop_when_solved)

    def generation(self, mode: str) -> dict:
        cfg, lay, N, rng = self.cfg, self.prob.layout, self.cfg.pop_size, self.rng
        obj, hits = phase_objective(self.A, mode)
        ia, ib = parents(rank_order(hits, obj), N // 2, rng, cfg.tournament_k)
        kids = crossover(self.pop[ia], self.pop[ib], lay, mode, rng, cfg.blend_prob,
                         cfg.circular_blend)
        kids = mutate(kids, lay, mode, rng, cfg.mutation_rate, cfg.mutation_min_deg,
                      cfg.mutation_max_deg)
        K = self.prob.assess(kids)
        self.evals += N
        pool, PA = np.concatenate([self.pop, kids]), Assessment.concat(self.A, K)
        obj, hits = phase_objective(PA, mode)
        keep = survivors(hits, obj, N, rng, cfg.infeasible_fraction,
                         cfg.survival == "pairwise")
        self.gen += 1
        # best whole limb so far (a child may hold it even when its phase ranks it low)
        j = int(np.argmin(_limb_key(K)))
        if _limb_key(Assessment.concat(self.best_a, K.take(np.array([j]))))[1] == 0:
            self.best, self.best_a = kids[j].copy(), K.take(np.array([j]))
        self.pop, self.A = pool[keep], PA.take(keep)
        self.history.append(self.best.copy())
        self.note_solution()
        row = _stats_row(self.gen, mode, self.evals, time.perf_counter() - self.t0, self.pop,
                         self.A, self.best_a)
        row["restarts"] = self.restarts
        self.stats.append(row)
        return row


def evolve(cfg: ArmIKConfig, seed: int, problem: ArmIKProblem | None = None,
           on_generation: Callable[[dict], None] | None = None) -> RunResult:
    """Run the schedule with ``numpy.random.default_rng(seed)``; time includes the heuristics.

    When the whole-limb phase gains less than 1% in ``restart_after`` generations, the
    schedule restarts from a fresh population (the best limb found so far is kept).
    """
    t0 = time.perf_counter()
    prob = problem if problem is not None else ArmIKProblem(cfg)
    run = _Run(cfg, prob, seed, t0)
    restarts, whole_left = -1, cfg.whole_generations
    while not run.done and (restarts < 0 or whole_left > 0):
        restarts += 1
        run.restarts = restarts
        if restarts:
            run.fresh_population()
        for mode, n_gen in (("arm", cfg.arm_generations), ("fingers", cfg.finger_generations)):
            for _ in range(n_gen):
                if run.done:
                    break
                row = run.generation(mode)
                if on_generation is not None:
                    on_generation(row)
        mark, mark_gen = np.inf, run.gen
        while whole_left > 0 and not run.done:
            d = float(run.A.distance[np.argmin(_limb_key(run.A))])
            if d < 0.99 * mark:
                mark, mark_gen = d, run.gen
            elif cfg.restart_after and run.gen - mark_gen >= cfg.restart_after:
                break
            whole_left -= 1
            row = run.generation("whole")
            if on_generation is not None:
                on_generation(row)
    return RunResult(prob, run.best, run.best_a, bool(run.best_a.solved[0]), run.solved_at,
                     run.gen, run.evals, time.perf_counter() - t0, np.array(run.history),
                     run.stats, max(restarts, 0), run.pop, run.A.distance, run.solved_cpu)


def _stats_row(gen: int, mode: str, evals: int, t: float, pop: np.ndarray, A: Assessment,
               best_a: Assessment) -> dict:
    obj, hits = phase_objective(A, mode)
    r = rank_order(hits, obj)
    b = int(np.argmin(r))
    feas = hits == 0
    return {
        "generation": gen, "phase": mode, "evaluations": evals, "time_s": round(t, 4),
        "best_objective": float(obj[b]), "best_intersections": int(hits[b]),
        "best_feasible_objective": float(obj[feas].min()) if feas.any() else float("nan"),
        "mean_objective": float(obj.mean()), "var_objective": float(obj.var()),
        "mean_intersections": float(hits.mean()), "var_intersections": float(hits.var()),
        "originality": np.unique(pop, axis=0).shape[0] / pop.shape[0],
        "feasible_fraction": float(feas.mean()),
        "best_limb_distance": float(best_a.distance[0]),
        "best_limb_intersections": int(best_a.intersections[0]),
        "best_limb_max_tip_error": float(best_a.tip_error[0].max()),
        "solved": int(best_a.solved[0]),
    }
