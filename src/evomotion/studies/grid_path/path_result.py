"""The outcome of a grid-path run: the best path (repaired when enabled), its length, validity
and gap to the exact optima (the ``best.json`` keys).

The paper's method needs the valid initial paths and the validity-keeping mutation of
:mod:`.operators`; the problem supplies both (``initial_population``, ``mutate``) and the
generic ask/tell driver of :mod:`evomotion.run.ask_tell` passes them to the optimizer, so a
grid-path run is an ordinary run of the engine (one stats row per generation = one sweep).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from evomotion.studies.grid_path.geometry import polyline_segments_valid
from evomotion.studies.grid_path.problem import GridPathProblem
from evomotion.studies.grid_path.repair import repair_population
from evomotion.studies.grid_path.solvers import Solution


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


def path_of(problem: GridPathProblem, best_x: np.ndarray, best_cost: float,
            pop: np.ndarray, pcost: np.ndarray) -> tuple[np.ndarray, float, bool]:
    """Waypoints, length and validity of the best path (repaired with the population's
    paths when ``problem.repair``)."""
    pts = problem.decode(best_x[None])[0]
    if problem.cfg.repair:
        polys = np.concatenate([pts[None], problem.decode(pop)])
        pts, _ = repair_population(problem.map.blocked, polys, np.r_[best_cost, pcost],
                                   problem.cfg.repair_paths, problem.cfg.repair_radius)
    rule = "open" if problem.cfg.repair else problem.rule
    valid = bool(polyline_segments_valid(problem.map.blocked, pts[None], rule).all())
    length = float(np.hypot(*np.diff(pts, axis=0).T).sum())
    return pts, length, valid


def outcome(problem: GridPathProblem, driver: Any, state: Any, rows: list[dict],
            generations: int, evaluations: int, seconds: float) -> PathResult:
    bx, bc = driver.best(state)
    pop, pcost = driver.opt.population(state)
    pts, length, valid = path_of(problem, bx, bc, pop, pcost)
    hist = np.array([r["best_so_far"] for r in rows]) if rows else np.array([bc])
    conv = int(np.argmax(hist <= bc + 1e-12))
    return PathResult(pts, length, valid, float(bc), bx, generations, evaluations, conv,
                      seconds, rows)


def best_record(res: PathResult | Any, optima: dict[str, Solution]) -> dict[str, Any]:
    """The study keys of ``best.json``: waypoints, length, valid, optima, gap_percent."""
    return {
        "waypoints": np.asarray(res.waypoints).tolist(),
        "length": res.length,
        "valid": res.valid,
        "optima": {k: s.length for k, s in optima.items()},
        "gap_percent": {k: 100.0 * (res.length / s.length - 1.0) for k, s in optima.items()},
    }


