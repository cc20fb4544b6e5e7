"""The arm-ik run driver: seed 001's multi-phase schedule written to a run folder.

``run_schedule(problem_cfg, seed, out_dir)`` writes ``config.toml`` (unless the CLI already
did), ``stats.csv`` (one row per generation), ``best.json``, ``log.txt``, ``board.png`` and
``best.gif``. It returns 0 when solved and :data:`EXIT_UNSOLVED` (3) otherwise, after printing
``no solution found`` with the best error reached.
"""

from __future__ import annotations

import csv
import dataclasses
from pathlib import Path

import numpy as np
import tomli_w

from evomotion.run.folder import atomic_write_text, write_json
from evomotion.studies.arm_ik.problem import ArmIKConfig
from evomotion.studies.arm_ik.schedule import STATS_COLUMNS, RunResult, evolve

EXIT_UNSOLVED = 3


def best_record(res: RunResult, seed: int) -> dict:
    """``best.json`` content; the first seven keys are a stable interface for other tools."""
    a = res.best_assessment
    arm, fingers = res.problem.layout.split(res.best)
    return {
        "arm_deg": arm,
        "fingers_deg": fingers,
        "assignment": a.assignment[0].tolist(),
        "tips": a.tips[0].tolist(),
        "error": float(a.tip_error[0].sum()),
        "intersections": int(a.intersections[0]),
        "solved": bool(a.solved[0]),
        "max_tip_error": float(a.tip_error[0].max()),
        "tolerance": res.problem.tol,
        "scenario": res.problem.scn.name,
        "seed": seed,
        "time_to_solution_s": res.time_to_solution_s,
        "generations": res.generations,
        "evaluations": res.evaluations,
        "restarts": res.restarts,
    }


def run_schedule(cfg: ArmIKConfig, seed: int, out_dir: Path | str, quiet: bool = True) -> int:
    """Run the schedule and write the run folder; 0 if solved, 3 (``EXIT_UNSOLVED``) if not."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if not (out / "config.toml").exists():
        data = {"study": "arm-ik", "run": {"seed": seed}, "problem": dataclasses.asdict(cfg)}
        atomic_write_text(out / "config.toml", tomli_w.dumps(data))
    with open(out / "log.txt", "w", encoding="utf-8") as log, \
            open(out / "stats.csv", "w", newline="", encoding="utf-8") as fh:
        writer = csv.DictWriter(fh, fieldnames=STATS_COLUMNS)
        writer.writeheader()
        last_phase = [""]

        def on_generation(row: dict) -> None:
            writer.writerow(row)
            if row["phase"] != last_phase[0]:
                last_phase[0] = row["phase"]
                log.write(f"generation {row['generation']}: {row['phase']} phase\n")

        res = evolve(cfg, seed, on_generation=on_generation)
        msg = _summary(res)
        log.write(msg + "\n")
    rec = best_record(res, seed)
    write_json(out / "best.json", rec)
    if cfg.pictures:
        from evomotion.studies.arm_ik.views import save_board, save_gif

        feasible = res.best if rec["intersections"] == 0 else None
        title = f"{res.problem.scn.name}: error {rec['error']:.4g}, " \
                f"{rec['intersections']} intersections, solved {rec['solved']}"
        save_board(res.problem, _best_in_population(res), feasible, out / "board.png", title)
        save_gif(res.problem, res.history, out / "best.gif", cfg.gif_frames)
    if not res.solved or not quiet:
        print(msg)
    return 0 if res.solved else EXIT_UNSOLVED


def _summary(res: RunResult) -> str:
    a = res.best_assessment
    err = float(a.tip_error[0].sum())
    if res.solved:
        return (f"solved {res.problem.scn.name} in {res.time_to_solution_s:.3f} s "
                f"({res.generations} generations, {res.restarts} restarts): error {err:.4g}")
    return (f"no solution found: best error {err:.6g} (max tip error "
            f"{a.tip_error[0].max():.4g}, tolerance {res.problem.tol:.4g}, "
            f"{int(a.intersections[0])} intersections) after {res.generations} generations")


def _best_in_population(res: RunResult) -> np.ndarray:
    """The best limb by distance alone, intersections ignored (the seed's blue limb)."""
    if res.final_population is None or res.final_distance is None:
        return res.best
    i = int(np.argmin(res.final_distance))
    if res.final_distance[i] < res.best_assessment.distance[0]:
        return res.final_population[i]
    return res.best
