"""Seconds per generation of ``humanoid-walk`` with and without a setting (``--vary``:
``problem.symmetric`` false / true, or ``problem.capture_gain`` 0 / 1), run back to back on
this machine (the ratio is what to report; these VMs are noisy): each setting evolves
``--generations`` generations from the same seed, everything else the study's default, and
the script prints wall seconds and environment steps per generation. Since 2026-12-06's
fifteenth session the NAO's default has capture steps (gain 1), so ``--vary symmetric`` times
both with them, unlike the ratios measured before it.

    python benchmarks/walk_generation_time.py --generations 40 [--seed 0] [--threads 2]
        [--vary symmetric|capture_gain]
"""

from __future__ import annotations

import argparse
import csv
import subprocess
import sys
import tempfile
import time
from pathlib import Path

VARY = {"symmetric": ("false", "true"), "capture_gain": ("0.0", "1.0")}


def one(out: Path, key: str, value: str, generations: int, seed: int, threads: int) -> dict:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "humanoid-walk", "--out",
                    str(out), "--set", f"run.seed={seed}", "--set",
                    f"run.generations={generations}", "--set",
                    f"problem.{key}={value}", "--set",
                    f"problem.threads={threads}", "--set", "run.videos=false", "--quiet"],
                   check=True)
    wall = time.perf_counter() - t0
    with open(out / "stats.csv") as f:
        rows = list(csv.DictReader(f))
    steps = float(rows[-1]["env_steps"])
    return {"value": value, "wall_s": wall, "s_per_generation": wall / len(rows),
            "env_steps_per_generation": steps / len(rows)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--generations", type=int, default=40)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--vary", choices=sorted(VARY), default="symmetric")
    a = ap.parse_args()
    values = VARY[a.vary]
    with tempfile.TemporaryDirectory() as tmp:
        rows = [one(Path(tmp) / v, a.vary, v, a.generations, a.seed, a.threads)
                for v in values]
    print(f"| {a.vary} | s / generation | env steps / generation |")
    print("|---|---|---|")
    for r in rows:
        print(f"| {r['value']} | {r['s_per_generation']:.2f} | "
              f"{r['env_steps_per_generation']:,.0f} |")
    t = rows[1]["s_per_generation"] / rows[0]["s_per_generation"]
    e = rows[1]["env_steps_per_generation"] / rows[0]["env_steps_per_generation"]
    print(f"ratio {a.vary} {values[1]} / {values[0]}: {t:.2f} s per generation, "
          f"{e:.2f} env steps")


if __name__ == "__main__":
    main()
