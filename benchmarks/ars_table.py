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
import concurrent.futures
import csv
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: task -> (threshold, paper's mean episodes). Thresholds: Mania et al. 2018 (Table 1); the
#: episode figures are recalled, partly confirmed (/shared/reference/policy-search.md). ARS runs
#: with ``--preset paper``: the paper's hyperparameters of each task (V1-t on Swimmer), the
#: gym study's ``PAPER_ARS_BY_ENV``.
TASKS = {
    "Swimmer": (325, 427),
    "Hopper": (3120, 1973),
    "HalfCheetah": (3430, 1707),
    "Walker2d": (4390, 24000),
    "Ant": (3580, 20800),
    "Humanoid": (6000, 142600),
}

#: task -> parameters of its linear policy (v5 observation x action sizes)
PARAMS = {"Swimmer": 8 * 2, "Hopper": 11 * 3, "HalfCheetah": 17 * 6, "Walker2d": 17 * 6,
          "Ant": 105 * 8, "Humanoid": 348 * 17}


def settings(task: str, method: str) -> list[str]:
    """The ``evomotion run gym`` arguments of ``method`` on ``task``."""
    env = ["--set", f"problem.env={task}-v5"]
    if method == "default":  # the study's defaults on the task, nothing else set
        return env
    if method == "ars":  # the paper's setting of the task
        return [*env, "--preset", "paper"]
    # the other methods see what ARS's rows saw: V1 (not normalised) on Swimmer, V2 elsewhere
    norm = ["--set", f"problem.normalize={'false' if task == 'Swimmer' else 'true'}"]
    if method == "openai_es":  # Salimans et al. 2017's setting scaled to a 2-core budget
        return [*env, "--set", "algorithm.name=openai_es", "--set", "algorithm.pop_size=40",
                "--set", "algorithm.sigma=0.02", "--set", "algorithm.learning_rate=0.01", *norm]
    if method == "cmaes":  # the study's default: CMA-ES from 0, sigma 0.1 (of the +-100 box)
        return [*env, "--set", "algorithm.name=cmaes", "--set", "algorithm.sigma0=0.0005",
                "--set", "algorithm.x0=center", *norm]
    if method == "pgpe":  # PGPE with ClipUp, Toklu et al. 2020's linear-policy setting:
        # v_max 0.015, step 0.5 v_max, stdev learning rate 0.1, initial radius 0.27 (|sigma|)
        n = PARAMS[task]
        return [*env, "--set", "algorithm.name=pgpe", "--set", "algorithm.pop_size=100",
                "--set", "algorithm.max_speed=0.015",
                "--set", "algorithm.center_learning_rate=0.0075",
                "--set", f"algorithm.stdev_init={0.27 / n ** 0.5:.6g}", *norm]
    raise SystemExit(f"unknown method {method!r}; available: default, ars, openai_es, cmaes, pgpe")


def one_run(task: str, method: str, seed: int, budget_s: float, workers: int,
            extra: tuple[str, ...] = ()) -> dict:
    threshold = TASKS[task][0]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        cmd = [sys.executable, "-m", "evomotion.cli", "run", "gym", "--out", str(out),
               "--set", f"run.seed={seed}", "--set", f"run.target={threshold}",
               "--set", f"run.wall_seconds={budget_s}", "--set", "run.generations=100000000"]
        cmd += ["--set", "run.evaluator=process", "--set", f"run.workers={workers}"] \
            if workers > 1 else ["--set", "run.evaluator=serial"]
        cmd += settings(task, method)
        for s in extra:
            cmd += ["--set", s]
        t0 = time.perf_counter()
        with tempfile.TemporaryFile() as err:
            proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err)
            # this run's own CPU (with its evaluation processes), even with runs in parallel
            _, status, usage = os.wait4(proc.pid, 0)
            proc.returncode = os.waitstatus_to_exitcode(status)
            err.seek(0)
            stderr = err.read().decode(errors="replace")
        wall = time.perf_counter() - t0
        cpu = usage.ru_utime + usage.ru_stime
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
            "env_steps_run": int(float(rows[-1].get("env_steps") or 0)) if rows else 0,
            "wall_s": wall, "cpu_s": cpu, "stderr": stderr[-500:] if proc.returncode
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
    ap.add_argument("--jobs", type=int, default=1, help="runs at the same time")
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--set", action="append", default=[], dest="extra",
                    help="another KEY=VALUE for every run (e.g. problem.eval_episodes=1)")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--report", nargs="+", type=Path, default=None,
                    help="print the table of these --json files (no runs)")
    a = ap.parse_args()
    if a.report:
        print_table([r for f in a.report for r in json.loads(f.read_text())])
        return
    cases = []
    for task in a.tasks.split(","):
        if task not in TASKS:
            raise SystemExit(f"unknown task {task!r}; available: {', '.join(TASKS)}")
        for method in a.methods.split(","):
            settings(task, method)  # an unknown method: refused before any run
            cases += [(task, method, a.first_seed + s) for s in range(a.seeds)]
    runs = []
    with concurrent.futures.ThreadPoolExecutor(max(1, a.jobs)) as pool:
        futures = [pool.submit(one_run, t, m, s, a.budget, a.workers, tuple(a.extra))
                   for t, m, s in cases]
        for f in concurrent.futures.as_completed(futures):
            r = f.result()
            runs.append(r)
            print(f"{r['task']} {r['method']} seed {r['seed']}: "
                  f"{'reached' if r['reached'] else 'not'} (best {r['best_return']:.0f}, "
                  f"episodes {r['episodes']}, {r['wall_s']:.0f} s)", file=sys.stderr, flush=True)
            if a.json:
                a.json.write_text(json.dumps(runs, indent=1))
    print_table(runs)


def print_table(runs: list[dict]) -> None:
    """The markdown table of ``runs`` (several invocations' JSON files may be merged)."""
    print("| task (v5) | threshold | method | reached | episodes to threshold: median (range) "
          "| wall s | CPU s | episodes run (not reached) | best return: median (range) "
          "| paper V2-t episodes |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    keys = list(dict.fromkeys((r["task"], r["method"]) for r in runs))
    for task, method in keys:
        rs = [r for r in runs if r["task"] == task and r["method"] == method]
        ok = [r for r in rs if r["reached"]]
        not_ok = [r["episodes_run"] for r in rs if not r["reached"]]
        print(f"| {task} | {TASKS[task][0]} | {method} | {len(ok)}/{len(rs)} | "
              f"{med_range([r['episodes'] for r in ok])} | "
              f"{med_range([r['wall_s'] for r in ok])} | "
              f"{med_range([r['cpu_s'] for r in ok])} | "
              f"{', '.join(f'{e:,}' for e in sorted(not_ok)) or '–'} | "
              f"{med_range([r['best_return'] for r in rs])} | {TASKS[task][1]:,} |")


if __name__ == "__main__":
    main()
