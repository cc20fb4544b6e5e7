"""The step and the walk on robots the project did not build its studies for (issue 19).

    python benchmarks/bench_robots.py [--out runs/robots] [--only NAME ...]

Runs, through ``evomotion.run`` (the CLI's run loop), and prints one row per run:

- ``humanoid-step --robot op3`` and ``--robot dm-humanoid`` (the study's defaults: GA,
  population 100 x 80 generations; the 41 kg dm humanoid with a 3 s step of 6 intervals:
  with the default 2 s and 10 intervals the best of a run stepped backward): forward step,
  lateral drift, heading, falls;
- ``humanoid-walk --robot op3``, ``dm-humanoid`` and ``dm-quadruped`` (``--preset nominal``:
  CMA-ES, population 16, nominal world; 60-80 generations; ``walk_s = 6``): distance, speed,
  straightness, heading, falls.

Each run folder keeps its ``best.mp4`` (look at it) and ``best_replay.json``.
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
    "walk-op3": ("humanoid-walk", "op3", "nominal",
                 {"problem": {"walk_s": 6.0}, "run": {"generations": 80}}),
    "walk-dm-humanoid": ("humanoid-walk", "dm-humanoid", "nominal",
                         {"problem": {"walk_s": 6.0}, "run": {"generations": 60}}),
    "walk-dm-quadruped": ("humanoid-walk", "dm-quadruped", "nominal",
                          {"problem": {"walk_s": 6.0}, "run": {"generations": 60}}),
}


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


if __name__ == "__main__":
    main()
