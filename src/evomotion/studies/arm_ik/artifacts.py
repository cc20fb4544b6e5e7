"""What an arm-ik run hands over: its result (:class:`ArmResult`), the ``best.json`` keys,
``board.png``/``best.gif``, the summary line and exit code."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from evomotion.studies.arm_ik.problem import ArmIKProblem, Assessment
from evomotion.studies.arm_ik.schedule import ScheduleState, limb_key

EXIT_UNSOLVED = 3


@dataclass
class ArmResult:
    """Outcome of one schedule run; ``best`` is the best whole limb (first solution if any)."""

    problem: ArmIKProblem
    best: np.ndarray
    best_assessment: Assessment
    solved: bool
    time_to_solution_s: float | None
    time_to_solution_cpu_s: float | None
    generations: int
    evaluations: int
    restarts: int
    history: np.ndarray  # (generations + 1, dim): best whole limb after each generation
    final_population: np.ndarray
    final_distance: np.ndarray  # whole-limb objective of the final population


def result_of(problem: ArmIKProblem, s: ScheduleState, evaluations: int) -> ArmResult:
    solved = bool(s.best_a.solved[0])
    return ArmResult(problem, s.best_x, s.best_a, solved,
                     s.solved_s if solved else None, s.solved_cpu_s if solved else None,
                     max(s.generation, 0), evaluations, s.restarts, s.history, s.pop,
                     s.assessment.distance)


def best_record(ctx: Any) -> dict[str, Any]:
    """The arm-ik keys of ``best.json`` (after the engine's envelope)."""
    r = result_of(ctx.problem, ctx.state, ctx.evaluations)
    a = r.best_assessment
    arm, fingers = r.problem.layout.split(r.best)
    return {
        "arm_deg": arm,
        "fingers_deg": fingers,
        "assignment": a.assignment[0].tolist(),
        "tips": a.tips[0].tolist(),
        "error": float(a.tip_error[0].sum()),
        "intersections": int(a.intersections[0]),
        "solved": bool(a.solved[0]),
        "max_tip_error": float(a.tip_error[0].max()),
        "tolerance": r.problem.tol,
        "scenario": r.problem.scn.name,
        "time_to_solution_s": r.time_to_solution_s,
        "restarts": r.restarts,
    }


def summary(r: ArmResult) -> str:
    a = r.best_assessment
    err = float(a.tip_error[0].sum())
    if r.solved:
        return (f"solved {r.problem.scn.name} in {r.time_to_solution_s:.3f} s "
                f"({r.generations} generations, {r.restarts} restarts): error {err:.4g}")
    return (f"no solution found: best error {err:.6g} (max tip error "
            f"{a.tip_error[0].max():.4g}, tolerance {r.problem.tol:.4g}, "
            f"{int(a.intersections[0])} intersections) after {r.generations} generations")


def finalize(ctx: Any) -> int:
    """``board.png`` and ``best.gif`` (when ``problem.pictures``), the summary line; exit 3
    when no solution was found."""
    r = result_of(ctx.problem, ctx.state, ctx.evaluations)
    cfg = ctx.problem.cfg
    if cfg.pictures and r.generations >= 0 and len(r.history):
        from evomotion.studies.arm_ik.views import save_board, save_gif

        hits = int(r.best_assessment.intersections[0])
        feasible = r.best if hits == 0 else None
        title = (f"{r.problem.scn.name}: error {float(r.best_assessment.tip_error[0].sum()):.4g}"
                 f", {hits} intersections, solved {r.solved}")
        save_board(r.problem, _best_in_population(r), feasible, ctx.out_dir / "board.png",
                   title)
        save_gif(r.problem, r.history, ctx.out_dir / "best.gif", cfg.gif_frames)
    ctx.log(summary(r))
    return 0 if r.solved else EXIT_UNSOLVED


def _best_in_population(r: ArmResult) -> np.ndarray:
    """The best limb by distance alone, intersections ignored (the paper's blue limb)."""
    if not len(r.final_distance):
        return r.best
    i = int(np.argmin(r.final_distance))
    if r.final_distance[i] < r.best_assessment.distance[0]:
        return r.final_population[i]
    return r.best


__all__ = ["ArmResult", "EXIT_UNSOLVED", "best_record", "finalize", "limb_key", "result_of",
           "summary"]
