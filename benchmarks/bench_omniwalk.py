"""The omnidirectional walk controller's figures (issue 34): per seed, evolve with the default
settings (timed), then ``humanoid-walk compare`` on unseen perturbed worlds of random
commands and the top-speed tests; a table per seed and the means over seeds.

    python benchmarks/bench_omniwalk.py --seeds 0 1 2 --out /tmp/omniwalk \
        [--worlds 100] [--duration 60] [--reuse] [--set problem.command_feedback=true]

``--reuse`` measures runs already in ``OUT/seed-N`` instead of evolving them again. One run at
a time, all cores (2 here); write the printed table into benchmarks/README.md and
docs/humanoid-walk.md.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np


def evolve(out: Path, seed: int, sets: tuple[str, ...] = ()) -> float:
    t0 = time.perf_counter()
    extra = [a for s in sets for a in ("--set", s)]
    subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "humanoid-walk", "--out",
                    str(out), "--set", f"run.seed={seed}", *extra, "--quiet"], check=True)
    return time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--worlds", type=int, default=100)
    ap.add_argument("--duration", type=float, default=60.0)
    ap.add_argument("--reuse", action="store_true")
    ap.add_argument("--set", action="append", default=[], dest="sets",
                    help="another KEY=VALUE for every run (problem.command_feedback=true)")
    args = ap.parse_args()
    from evomotion.studies.humanoid_omniwalk.compare import compare, table

    rows = []
    for seed in args.seeds:
        run = args.out / f"seed-{seed}"
        wall = None
        if not (args.reuse and (run / "policy.npz").is_file()):
            wall = evolve(run, seed, tuple(args.sets))
        t0 = time.perf_counter()
        res = compare(run, args.worlds, args.duration, seed=0)
        res["evolve_wall_s"] = wall
        res["compare_wall_s"] = time.perf_counter() - t0
        (run / "compare.json").write_text(json.dumps(res, indent=1) + "\n")
        print(f"## seed {seed}: evolved in "
              f"{'(reused)' if wall is None else f'{wall / 60:.1f} min'}\n")
        print(table(res) + "\n", flush=True)
        rows.append(res)
    print(f"## mean over seeds {args.seeds}\n")
    print("| controller | survival | relative speed error (steady) | relative yaw-rate error "
          "(steady) | forward | backward | left | right | turn left | turn right |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for key in ("controller", "engine"):
        def m(f):  # None (a quantity never commanded) counts as nan
            values = [f(r[key]) for r in rows]
            return float(np.mean([np.nan if v is None else v for v in values]))

        def ts(name, axis):  # a forward-only run's slowest test is "forward_min"
            return m(lambda r: r["top_speeds"].get(name, r["top_speeds"].get("forward_min"))
                     [axis])
        print(f"| {key} | {100 * m(lambda r: r['survival']):.0f} % | "
              f"{100 * m(lambda r: r['relative_speed_error']):.0f} % "
              f"({100 * m(lambda r: r['steady_relative_speed_error']):.0f} %) | "
              f"{100 * m(lambda r: r['relative_yaw_rate_error']):.0f} % "
              f"({100 * m(lambda r: r['steady_relative_yaw_rate_error']):.0f} %) | "
              f"{ts('forward', 'vx_mps'):.2f} m/s | {ts('backward', 'vx_mps'):.2f} m/s | "
              f"{ts('left', 'vy_mps'):.2f} m/s | {ts('right', 'vy_mps'):.2f} m/s | "
              f"{ts('turn_left', 'yaw_rate_dps'):.0f} deg/s | "
              f"{ts('turn_right', 'yaw_rate_dps'):.0f} deg/s |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
