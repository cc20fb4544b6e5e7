"""ARS's Table 1 on today's environments: training episodes until the centre's return reaches
the paper's threshold, on the Gymnasium v5 tasks, with ARS V2-t (V1-t on Swimmer, as the
paper) and OpenAI-ES, over several seeds (issue 33).

Each (task, method, seed) is one ``evomotion run gym`` with ``run.target`` = the threshold and
a wall-clock budget; the episodes are ``stats.csv``'s ``train_episodes`` at the first
generation whose ``centre_return`` (the mean return of the centre on ``problem.eval_episodes``
unseen episodes) reaches the threshold. Printed: a markdown table with the median and range of
episodes, wall and CPU seconds over the seeds that reached it, how many did, and the paper's
figure beside. ``--json`` keeps every run.

    python benchmarks/ars_table.py --tasks Swimmer,Hopper --seeds 5 --budget 900
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: task -> (threshold, ARS V2-t settings (alpha, N, b, nu, normalise), paper's mean episodes)
#: Thresholds and settings: Mania et al. 2018 (Table 1; hyperparameters as their public code's
#: and a widely used RL zoo's "close to the paper" values, /shared/reference/policy-search.md);
#: the episode figures are recalled, partly confirmed (see that file).
TASKS = {
    "Swimmer": (325, (0.02, 1, 1, 0.01, False), 427),
    "Hopper": (3120, (0.01, 8, 4, 0.025, True), 1973),
    "HalfCheetah": (3430, (0.02, 32, 4, 0.03, True), 1707),
    "Walker2d": (4390, (0.03, 40, 30, 0.025, True), 24000),
    "Ant": (3580, (0.015, 60, 20, 0.025, True), 20800),
    "Humanoid": (6000, (0.02, 230, 230, 0.0075, True), 142600),
}


def settings(task: str, method: str) -> list[str]:
    _, (alpha, n, b, nu, norm), _ = TASKS[task]
    common = [f"problem.env={task}-v5", f"problem.normalize={'true' if norm else 'false'}"]
    if method == "ars":
        return common + ["algorithm.name=ars", f"algorithm.pop_size={2 * n}",
                         f"algorithm.step_size={alpha}", f"algorithm.noise_std={nu}",
                         f"algorithm.top_directions={b}"]
    if method == "openai_es":  # Salimans et al. 2017's setting scaled to a 2-core budget
        return common + ["algorithm.name=openai_es", "algorithm.pop_size=40",
                         "algorithm.sigma=0.02", "algorithm.learning_rate=0.01"]
    raise SystemExit(f"unknown method {method!r}; available: ars, openai_es")


def one_run(task: str, method: str, seed: int, budget_s: float, workers: int) -> dict:
    threshold = TASKS[task][0]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        cmd = [sys.executable, "-m", "evomotion.cli", "run", "gym", "--out", str(out),
               "--set", f"run.seed={seed}", "--set", f"run.target={threshold}",
               "--set", f"run.wall_seconds={budget_s}", "--set", "run.generations=100000000"]
        if workers > 1:
            cmd += ["--set", "run.evaluator=process", "--set", f"run.workers={workers}"]
        for s in settings(task, method):
            cmd += ["--set", s]
        t0, c0 = time.perf_counter(), os.times()
        proc = subprocess.run(cmd, capture_output=True, text=True)
        c1 = os.times()
        wall = time.perf_counter() - t0
        cpu = (c1.children_user + c1.children_system) - (c0.children_user + c0.children_system)
        rows = []
        if (out / "stats.csv").is_file():
            with open(out / "stats.csv") as f:
                rows = list(csv.DictReader(f))
    reached = next((r for r in rows if float(r["centre_return"]) >= threshold), None)
    best = max((float(r["centre_return"]) for r in rows), default=float("nan"))
    return {"task": task, "method": method, "seed": seed, "exit": proc.returncode,
            "reached": reached is not None, "best_return": best,
            "episodes": int(reached["train_episodes"]) if reached else None,
            "episodes_run": int(rows[-1]["train_episodes"]) if rows else 0,
            "wall_s": wall, "cpu_s": cpu, "stderr": proc.stderr[-500:] if proc.returncode
            not in (0, 3) else ""}


def med_range(values: list[float]) -> str:
    if not values:
        return "–"
    v = sorted(values)
    mid = v[len(v) // 2] if len(v) % 2 else 0.5 * (v[len(v) // 2 - 1] + v[len(v) // 2])
    return f"{mid:,.0f} ({v[0]:,.0f}–{v[-1]:,.0f})"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", default="Swimmer,Hopper")
    ap.add_argument("--methods", default="ars,openai_es")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--budget", type=float, default=900.0, help="wall seconds per run")
    ap.add_argument("--workers", type=int, default=2, help="evaluation processes per run")
    ap.add_argument("--json", type=Path, default=None)
    a = ap.parse_args()
    runs = []
    for task in a.tasks.split(","):
        if task not in TASKS:
            raise SystemExit(f"unknown task {task!r}; available: {', '.join(TASKS)}")
        for method in a.methods.split(","):
            for seed in range(a.seeds):
                runs.append(one_run(task, method, seed, a.budget, a.workers))
                r = runs[-1]
                print(f"{task} {method} seed {seed}: {'reached' if r['reached'] else 'not'} "
                      f"(best {r['best_return']:.0f}, episodes {r['episodes']}, "
                      f"{r['wall_s']:.0f} s)", file=sys.stderr, flush=True)
                if a.json:
                    a.json.write_text(json.dumps(runs, indent=1))
    print("| task (v5) | threshold | method | reached | episodes: median (range) | wall s | "
          "CPU s | best return: median (range) | paper V2-t episodes |")
    print("|---|---|---|---|---|---|---|---|---|")
    for task in a.tasks.split(","):
        for method in a.methods.split(","):
            rs = [r for r in runs if r["task"] == task and r["method"] == method]
            ok = [r for r in rs if r["reached"]]
            print(f"| {task} | {TASKS[task][0]} | {method} | {len(ok)}/{len(rs)} | "
                  f"{med_range([r['episodes'] for r in ok])} | "
                  f"{med_range([r['wall_s'] for r in ok])} | "
                  f"{med_range([r['cpu_s'] for r in ok])} | "
                  f"{med_range([r['best_return'] for r in rs])} | {TASKS[task][2]:,} |")


if __name__ == "__main__":
    main()
