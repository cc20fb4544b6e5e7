"""Seconds per generation of ``humanoid-balance`` under two ways of choosing the export, run
back to back on this machine (the ratio is what to report; these VMs are noisy):

- ``centre 32``: the centre scored on 32 episodes every generation, the best such score
  exported, no validation (the default until 2026-12-07's twenty-second session);
- ``validated``: the centre scored on 8 episodes, every 10th generation's centre on 128 fixed
  validation episodes, the best validated centre exported (the default since).

Both evolve ``--generations`` generations (a multiple of 10, so that the validations are one in
ten) from the same seed, everything else the study's default, alternately ``--repeats`` times;
the script prints wall seconds and environment steps per generation, their ratios, and whether
the two searches were the same (``train_episodes`` and the candidates' returns in
``stats.csv``: the centre's episodes and the validation train nothing).

    python benchmarks/balance_validation_cost.py --generations 40 [--seed 0] [--repeats 1]
        [--threads 2]
"""

from __future__ import annotations

import argparse
import csv
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SETTINGS = {
    "centre 32": ("problem.eval_episodes=32", "problem.validate_every=0"),
    "validated": ("problem.eval_episodes=8", "problem.validate_every=10",
                  "problem.validate_episodes=128"),
}
SEARCH_COLUMNS = ("best", "mean", "median", "min", "max", "std", "train_episodes")


def one(out: Path, sets: tuple[str, ...], generations: int, seed: int,
        threads: int) -> tuple[dict, list[dict]]:
    args = [a for s in (f"run.seed={seed}", f"run.generations={generations}",
                        f"problem.threads={threads}", *sets) for a in ("--set", s)]
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "humanoid-balance", "--out",
                    str(out), *args, "--quiet"], check=True, cwd=tempfile.gettempdir())
    wall = time.perf_counter() - t0
    with open(out / "stats.csv") as f:
        rows = list(csv.DictReader(f))
    return ({"wall_s": wall, "s_per_generation": wall / len(rows),
             "env_steps_per_generation": float(rows[-1]["env_steps"]) / len(rows)},
            [{k: r[k] for k in SEARCH_COLUMNS} for r in rows])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--generations", type=int, default=40)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    if a.generations < 10 or a.generations % 10:
        ap.error("--generations: expected a multiple of 10, at least 10")
    times: dict[str, list[dict]] = {name: [] for name in SETTINGS}
    searches: dict[str, list] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(a.repeats):  # alternately, so that a slow spell hits both
            for name, sets in SETTINGS.items():
                out = Path(tmp) / f"{name.replace(' ', '-')}-{r}"
                t, search = one(out, sets, a.generations, a.seed, a.threads)
                times[name].append(t)
                searches.setdefault(name, search)
    print(f"humanoid-balance, {a.generations} generations, seed {a.seed}, "
          f"{a.threads} threads, median of {a.repeats}")
    print("| setting | s / generation | env steps / generation | each (s / gen) |")
    print("|---|---|---|---|")
    med = {}
    for name, ts in times.items():
        s = statistics.median(t["s_per_generation"] for t in ts)
        e = statistics.median(t["env_steps_per_generation"] for t in ts)
        med[name] = (s, e)
        each = ", ".join(f"{t['s_per_generation']:.2f}" for t in ts)
        print(f"| {name} | {s:.2f} | {e:.0f} | {each} |")
    (s0, e0), (s1, e1) = med["centre 32"], med["validated"]
    print(f"ratio validated / centre 32: time {s1 / s0:.2f}, env steps {e1 / e0:.2f}")
    same = searches["centre 32"] == searches["validated"]
    print(f"same search (candidates' returns, train episodes): {'yes' if same else 'NO'}")


if __name__ == "__main__":
    main()
