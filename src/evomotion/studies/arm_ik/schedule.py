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
    "best_limb_intersections", "best_limb_max_tip_error", "solved",
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


def _limb_key(a: Assessment) -> np.ndarray:
    return rank_order(a.intersections, a.distance)


def evolve(cfg: ArmIKConfig, seed: int, problem: ArmIKProblem | None = None,
           on_generation: Callable[[dict], None] | None = None) -> RunResult:
    """Run the schedule with ``numpy.random.default_rng(seed)``; time includes the heuristics."""
    t0 = time.perf_counter()
    prob = problem if problem is not None else ArmIKProblem(cfg)
    lay, N = prob.layout, cfg.pop_size
    rng = np.random.default_rng(seed)
    pop = prob.genome.sample(rng, N)
    A = prob.assess(pop)
    evals = N
    i = int(np.argmin(_limb_key(A)))
    best, best_a = pop[i].copy(), A.take(np.array([i]))
    history = [best.copy()]
    stats: list[dict] = []
    solved_at: float | None = None
    gen = 0
    phases = [("arm", cfg.arm_generations), ("fingers", cfg.finger_generations),
              ("whole", cfg.whole_generations)]
    done = bool(best_a.solved[0])
    if done:
        solved_at = time.perf_counter() - t0
    for mode, n_gen in phases:
        for _ in range(n_gen):
            if done or time.perf_counter() - t0 > cfg.wall_seconds:
                break
            obj, hits = phase_objective(A, mode)
            ia, ib = parents(rank_order(hits, obj), N // 2, rng, cfg.tournament_k)
            kids = crossover(pop[ia], pop[ib], lay, mode, rng, cfg.blend_prob, cfg.circular_blend)
            kids = mutate(kids, lay, mode, rng, cfg.mutation_rate, cfg.mutation_min_deg,
                          cfg.mutation_max_deg)
            K = prob.assess(kids)
            evals += N
            pool, PA = np.concatenate([pop, kids]), Assessment.concat(A, K)
            obj, hits = phase_objective(PA, mode)
            keep = survivors(hits, obj, N, rng, cfg.infeasible_fraction)
            gen += 1
            # best whole limb so far (the kids may hold it even if the phase ranks it low)
            j = int(np.argmin(_limb_key(K)))
            cand = Assessment.concat(best_a, K.take(np.array([j])))
            if _limb_key(cand)[1] == 0:
                best, best_a = kids[j].copy(), K.take(np.array([j]))
            pop, A = pool[keep], PA.take(keep)
            history.append(best.copy())
            if best_a.solved[0] and solved_at is None:
                solved_at = time.perf_counter() - t0
                done = cfg.stop_when_solved
            row = _stats_row(gen, mode, evals, time.perf_counter() - t0, pop, A, best_a)
            stats.append(row)
            if on_generation is not None:
                on_generation(row)
    return RunResult(prob, best, best_a, bool(best_a.solved[0]), solved_at, gen, evals,
                     time.perf_counter() - t0, np.array(history), stats)


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
