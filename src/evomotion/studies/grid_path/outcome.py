"""The grid-path run driver: the seed's cGA (or the panmictic GA) with its path operators.

The generic runner counts one ``tell`` as a generation and builds optimizers from the
genome alone; the seed's method needs the valid initial paths and the validity-keeping
mutation of :mod:`.operators`, and an asynchronous cGA sweep spans several ``ask``/``tell``
waves. :func:`evolve` therefore drives the ask/tell loop itself: one statistics row per
generation (one full sweep), the cGA built with ``mutate=operators.mutate``, the GA with its
registry mutation switched off and the same path mutation applied to its children.

Fitness batches (each ``ask``) go through ``evaluate`` (by default the problem in this process;
:func:`.study.run` passes an evaluator from :func:`evomotion.run.evaluators.make_evaluator`).
The validity checks inside the initialisation, the validity-keeping mutation and the final
repair are not fitness evaluations (they test single segments, by table lookup or geometry,
while re-drawing points) and stay in this process. The fitness of a path depends on that
path only, so results are bit-identical whichever evaluator splits the batches.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from evomotion.core.cellular_ga import CellularGA, CGAConfig
from evomotion.core.ga import GA, GAConfig
from evomotion.core.problem import Evaluation
from evomotion.run.stats import diversity, population_stats
from evomotion.studies.grid_path.geometry import polyline_segments_valid
from evomotion.studies.grid_path.problem import GridPathProblem
from evomotion.studies.grid_path.repair import repair_population
from evomotion.studies.grid_path.solvers import Solution, all_optima


@dataclass
class PathResult:
    """Outcome of one run: best path (after repair when enabled) and per-generation stats."""

    waypoints: np.ndarray
    length: float
    valid: bool
    fitness: float
    genome: np.ndarray
    generations: int
    evaluations: int
    converged_generation: int  # first generation at which the final best fitness was held
    seconds: float
    rows: list[dict[str, float]] = field(default_factory=list)


def make_optimizer(problem: GridPathProblem, alg: Any) -> tuple[Any, bool]:
    """The optimizer for ``alg`` and whether the driver must apply the path mutation."""
    if isinstance(alg, CGAConfig):
        return CellularGA(problem.genome, alg, mutate=problem.operators.mutate), False
    if isinstance(alg, GAConfig):
        return GA(problem.genome, dataclasses.replace(alg, mutation_rate=0.0)), True
    raise ValueError(f"grid-path supports the 'cga' and 'ga' algorithms, got {alg.name!r}")


def evolve(problem: GridPathProblem, alg: Any, seed: int, generations: int,
           on_generation: Callable[[dict[str, float]], None] | None = None,
           evaluate: Callable[[np.ndarray], Evaluation] | None = None) -> PathResult:
    """Run ``generations`` generations from the seed's valid initial paths; ``evaluate``
    maps a genome batch to its :class:`Evaluation` (default: ``problem.evaluate``)."""
    evaluate = evaluate or problem.evaluate
    rng = np.random.default_rng(seed)
    opt, outer_mutation = make_optimizer(problem, alg)
    ops = problem.operators
    t0 = time.perf_counter()
    state = opt.init(rng, ops.initial_population(alg.pop_size, rng))
    evals, gen, rows = 0, -1, []
    best_hist: list[float] = []
    while gen < generations:
        x, state = opt.ask(state, rng)
        if outer_mutation and gen >= 0:
            x = ops.mutate(x, rng, alg.mutation_rate)
        cost = np.asarray(evaluate(x).fitness, dtype=float)
        state = opt.tell(state, x, cost, rng)
        evals += len(x)
        if isinstance(opt, CellularGA) and not opt.end_of_generation(state):
            continue
        gen += 1
        _, pcost = opt.population(state)
        best = opt.best(state)[1]
        best_hist.append(best)
        row = {"generation": gen, "evaluations": evals, "best": float(np.min(pcost)),
               **population_stats(pcost), "best_so_far": best,
               "wall_s": round(time.perf_counter() - t0, 4),
               "diversity": diversity(opt.population(state)[0], problem.genome.span),
               "failed": 0}
        rows.append(row)
        if on_generation is not None:
            on_generation(row)
    bx, bc = opt.best(state)
    conv = int(np.argmax(np.asarray(best_hist) <= bc + 1e-12))
    pts = problem.decode(bx[None])[0]
    if problem.cfg.repair:
        pop, pcost = opt.population(state)
        polys = np.concatenate([pts[None], problem.decode(pop)])
        pts, _ = repair_population(problem.map.blocked, polys, np.r_[bc, pcost],
                                   problem.cfg.repair_paths, problem.cfg.repair_radius)
    rule = "open" if problem.cfg.repair else problem.rule
    valid = bool(polyline_segments_valid(problem.map.blocked, pts[None], rule).all())
    length = float(np.hypot(*np.diff(pts, axis=0).T).sum())
    return PathResult(pts, length, valid, float(bc), bx, gen, evals, conv,
                      time.perf_counter() - t0, rows)


def best_record(res: PathResult, optima: dict[str, Solution]) -> dict[str, Any]:
    """``best.json``: exactly the keys waypoints, length, valid, optima, gap_percent."""
    return {
        "waypoints": res.waypoints.tolist(),
        "length": res.length,
        "valid": res.valid,
        "optima": {k: s.length for k, s in optima.items()},
        "gap_percent": {k: 100.0 * (res.length / s.length - 1.0) for k, s in optima.items()},
    }


def solve_optima(problem: GridPathProblem) -> dict[str, Solution]:
    return all_optima(problem.map)
