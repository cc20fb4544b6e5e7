"""Seconds per generation of ``humanoid-walk`` with and without a setting (``--vary``:
``problem.symmetric`` false / true, or ``problem.capture_gain`` 0 / 1), run back to back on
this machine (the ratio is what to report; these VMs are noisy): each setting evolves
``--generations`` generations from the same seed, everything else the study's default, and
the script prints wall seconds and environment steps per generation. Since 2026-12-06's
fifteenth session the NAO's default has capture steps (gain 1), so ``--vary symmetric`` times
both with them, unlike the ratios measured before it.

``--baseline REV`` instead times the default at a git revision (its ``src`` exported, first on
``PYTHONPATH``) against this tree, alternately ``--repeats`` times each, and says whether the
two evolved the same controller (``policy.npz`` and ``stats.csv`` but its time columns): a
speed-up that must not change a result.

    python benchmarks/walk_generation_time.py --generations 40 [--seed 0] [--threads 2]
        [--vary symmetric|capture_gain]
    python benchmarks/walk_generation_time.py --generations 20 --baseline 77c6a41 [--repeats 3]
"""

from __future__ import annotations

import argparse
import csv
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from baseline import export  # noqa: E402

TIME_COLUMNS = ("wall_s", "evals_per_s")
VARY = {"symmetric": ("false", "true"), "capture_gain": ("0.0", "1.0")}


def one(out: Path, key: str | None, value: str, generations: int, seed: int, threads: int,
        src: Path | None = None) -> dict:
    env = dict(os.environ) if src is None else dict(os.environ, PYTHONPATH=str(src))
    setting = [] if key is None else ["--set", f"problem.{key}={value}"]
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "humanoid-walk", "--out",
                    str(out), "--set", f"run.seed={seed}", "--set",
                    f"run.generations={generations}", *setting, "--set",
                    f"problem.threads={threads}", "--set", "run.videos=false", "--quiet"],
                   check=True, env=env, cwd=tempfile.gettempdir())
    wall = time.perf_counter() - t0
    with open(out / "stats.csv") as f:
        rows = list(csv.DictReader(f))
    steps = float(rows[-1]["env_steps"])
    return {"value": value, "wall_s": wall, "s_per_generation": wall / len(rows),
            "env_steps_per_generation": steps / len(rows)}


def same_result(a: Path, b: Path) -> bool:
    """The same ``policy.npz`` bytes and ``stats.csv`` but for its time columns."""
    def stats(p: Path) -> list[dict]:
        with open(p / "stats.csv") as f:
            return [{k: v for k, v in r.items() if k not in TIME_COLUMNS}
                    for r in csv.DictReader(f)]
    return ((a / "policy.npz").read_bytes() == (b / "policy.npz").read_bytes()
            and stats(a) == stats(b))


def against_baseline(rev: str, generations: int, seed: int, threads: int,
                     repeats: int) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        src = export(rev, Path(tmp))
        times: dict[str, list[float]] = {"baseline": [], "this tree": []}
        same = True
        for r in range(repeats):  # alternately, so that a slow spell hits both
            runs = {}
            for side, tree in (("baseline", src), ("this tree", None)):
                out = Path(tmp) / f"{side.replace(' ', '-')}-{r}"
                times[side].append(one(out, None, "", generations, seed, threads,
                                       tree)["s_per_generation"])
                runs[side] = out
            same = same and same_result(runs["baseline"], runs["this tree"])
    print(f"| tree | s / generation (median of {repeats}) | each |")
    print("|---|---|---|")
    for side, ts in times.items():
        label = f"{side} ({rev})" if side == "baseline" else side
        print(f"| {label} | {statistics.median(ts):.2f} | "
              f"{', '.join(f'{t:.2f}' for t in ts)} |")
    ratio = statistics.median(times["this tree"]) / statistics.median(times["baseline"])
    print(f"ratio this tree / baseline: {ratio:.2f} s per generation; the same controller "
          f"and stats: {'yes' if same else 'NO'}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--generations", type=int, default=40)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--vary", choices=sorted(VARY), default="symmetric")
    ap.add_argument("--baseline", help="time the default at this git revision against "
                    "this tree instead of varying a setting")
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    if a.baseline:
        against_baseline(a.baseline, a.generations, a.seed, a.threads, a.repeats)
        return
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
