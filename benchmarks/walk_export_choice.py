"""Which of a run's exports walks best, judged the way a run could judge it itself: each
folder's ``policy.npz`` (snapshots of one run taken at its checkpoints: the best centre so far
at generation G, what a run stopped there exports) played on ``--episodes`` fresh episodes of
the training task (``problem.duration_s``, its worlds, pushes and command schedules; seeds from
2^39, apart from training's below 2^31 and ``compare``'s from 2^40), printing the mean return
(the fitness, with its standard error), survival, and each export's return less the last
folder's on the same episodes (paired, with its standard error: the episodes' own spread
cancels). Put beside ``humanoid-walk compare`` of
the same folders, it says whether choosing among a run's exports by such a validation would
pick the one that walks best in ``compare``'s 100 worlds x 60 s.

    python benchmarks/walk_export_choice.py SNAPSHOT... [--episodes 200] [--duration 8]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from evomotion.studies.humanoid_omniwalk.compare import _play, load_run

VALIDATION_SEED_BASE = 2**39


def validate(folder: Path, episodes: int, duration_s: float | None) -> dict:
    problem, policy, _ = load_run(folder, duration_s)
    m = _play(problem, policy.params, policy.obs_mean, policy.obs_std,
              VALIDATION_SEED_BASE + np.arange(episodes))  # compare's batched player
    problem.sim.close()
    r, v = m["return"], m["survived"]
    return {"return": float(r.mean()), "se": float(r.std(ddof=1) / math.sqrt(len(r))),
            "survived": float(v.mean()), "returns": r}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+", type=Path)
    ap.add_argument("--episodes", type=int, default=200)
    ap.add_argument("--duration", type=float, default=None,
                    help="episode length (s); default the run's problem.duration_s")
    a = ap.parse_args()
    if a.episodes < 2:
        ap.error(f"--episodes: expected at least 2 (a standard error needs two), got {a.episodes}")
    rows = []
    for f in a.folders:
        t0 = time.perf_counter()
        rows.append((f, validate(f, a.episodes, a.duration), time.perf_counter() - t0))
    last = rows[-1][1]["returns"]
    print(f"| export | validation return ({a.episodes} episodes) | survival | less the last "
          "(paired) | s |")
    print("|---|---|---|---|---|")
    for f, r, t in rows:
        d = r["returns"] - last
        print(f"| {f} | {r['return']:.4f} ± {r['se']:.4f} | {100 * r['survived']:.0f} % | "
              f"{d.mean():+.4f} ± {d.std(ddof=1) / math.sqrt(len(d)):.4f} | {t:.0f} |")


if __name__ == "__main__":
    sys.exit(main())
