"""The step and the walk on robots the project did not build its studies for (issue 19).

    python benchmarks/bench_robots.py [--out runs/robots] [--only NAME ...]

Runs, through ``evomotion.run`` (the CLI's run loop), and prints one row per run:

- ``humanoid-step --robot op3`` and ``--robot dm-humanoid`` (the study's defaults: GA,
  population 100 x 80 generations; the 41 kg dm humanoid with a 3 s step of 6 intervals:
  with the default 2 s and 10 intervals the best of a run stepped backward): forward step,
  lateral drift, heading, falls;
- ``humanoid-walk-open-loop --robot op3``, ``dm-humanoid`` and ``dm-quadruped``
  (``--preset nominal``:
  CMA-ES, population 16, nominal world; 60-80 generations; ``walk_s = 6``): distance, speed,
  straightness, heading, falls;
- ``humanoid-repertoire --robot op3`` and ``dm-humanoid`` (CMA-ME, the study's defaults but
  100 generations): cells filled, standing steps exported, QD-score, the best step, and a
  ``walk-to`` with the repertoire (error, fell).

Each run folder keeps its ``best.mp4`` (step, walk; look at it) or
``repertoire/contact_sheet.mp4`` and ``best_replay.json``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import evomotion as em

RUNS = {
    "step-dm-humanoid": ("humanoid-step", "dm-humanoid", None,
                         {"problem": {"motion_s": 3.0, "intervals": 6}}),
    "step-op3": ("humanoid-step", "op3", None, {}),
    "walk-op3": ("humanoid-walk-open-loop", "op3", "nominal",
                 {"problem": {"walk_s": 6.0}, "run": {"generations": 80}}),
    "walk-dm-humanoid": ("humanoid-walk-open-loop", "dm-humanoid", "nominal",
                         {"problem": {"walk_s": 6.0}, "run": {"generations": 60}}),
    "walk-dm-quadruped": ("humanoid-walk-open-loop", "dm-quadruped", "nominal",
                          {"problem": {"walk_s": 6.0}, "run": {"generations": 60}}),
    "repertoire-op3": ("humanoid-repertoire", "op3", None, {"run": {"generations": 100}}),
    "repertoire-dm-humanoid": ("humanoid-repertoire", "dm-humanoid", None,
                               {"run": {"generations": 100}}),
}
#: walk-to targets (x m, y m, theta deg) per repertoire robot: about three steps' worth
WALK_TO = {"op3": (0.3, 0.1, 30.0), "dm-humanoid": (0.3, 0.0, 20.0)}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default="runs/robots")
    p.add_argument("--only", nargs="*", default=list(RUNS))
    args = p.parse_args()
    for name in args.only:
        study, robot, preset, config = RUNS[name]
        config = {**config, "problem": {**config.get("problem", {}), "robot": robot}}
        out = Path(args.out) / name
        t0 = time.perf_counter()
        res = em.run(study, config, out, preset=preset)
        wall = time.perf_counter() - t0
        m = res.best_metrics
        if study == "humanoid-repertoire":
            print(json.dumps(_repertoire_row(name, robot, out, res, wall)), flush=True)
            continue
        replay = json.loads((out / "best_replay.json").read_text())
        row = {"run": name, "generations": res.generation, "wall_s": round(wall, 1),
               "forward_m": round(m["forward_m"], 3), "lateral_m": round(m["lateral_m"], 3),
               "heading_rad": round(m["heading_change_rad"], 3), "fell": bool(m["fell"])}
        if "speed_mps" in m:
            row.update(speed_mps=round(m["speed_mps"], 3),
                       straightness=round(m["straightness"], 3))
        row["video"] = (out / "best.mp4").is_file()
        row["replay_fell"] = replay["fell"]
        print(json.dumps(row), flush=True)


def _repertoire_row(name: str, robot: str, out: Path, res, wall: float) -> dict:
    from evomotion.studies.humanoid_repertoire.step_planning import walk_to

    stats = em.load_run(out).stats
    index = json.loads((out / "repertoire" / "index.json").read_text())
    x, y, th = WALK_TO[robot]
    w = walk_to(out, x, y, th, video=out / "walk_to.mp4")
    best = res.best_metrics
    return {"run": name, "generations": res.generation, "wall_s": round(wall, 1),
            "filled": int(stats["archive_size"][-1]), "cells": index["cells"],
            "standing_exported": len(index["entries"]),
            "qd_score": round(float(stats["qd_score"][-1]), 1),
            "best_objective": round(res.best_fitness, 3),
            "best_step": [round(best[k], 3) for k in ("dx_m", "dy_m", "dtheta_deg")],
            "walk_to": [x, y, th], "walk_to_steps": w["steps"],
            "walk_to_error_m": round(w["position_error_m"], 3),
            "walk_to_error_deg": round(w["heading_error_deg"], 1), "walk_to_fell": w["fell"],
            "video": (out / "repertoire" / "contact_sheet.mp4").is_file()}


if __name__ == "__main__":
    main()
