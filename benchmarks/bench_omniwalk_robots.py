"""humanoid-walk on other bipeds (issue 34, item 5): per robot and seed, evolve the walk
controller with the study's defaults on that robot (``--robot NAME``), timed; then, for the
evolved controller and the engine it started from (the fitted tape without feedback, open
loop):

- **forward** at 0.1, 0.2 and 0.3 m/s, each alone for 10 s in the nominal world without a
  push (ramped over the run's ramp): the walked velocity, the mean over the last half, and
  whether it fell;
- **nominal world, random commands**: ``--worlds`` schedules of ``--duration`` s of the run's
  random commands in the nominal world without pushes: survival;
- **perturbed worlds**: as ``humanoid-walk compare`` (unseen worlds, the run's pushes):
  survival and the relative speed error; and compare's top speeds (each direction alone at the
  run's range limit, nominal world).

    python benchmarks/bench_omniwalk_robots.py --robots op3 dm-humanoid --seeds 0 \
        --out /tmp/omniwalk-robots [--worlds 20] [--duration 60] [--reuse] [--threads 1] \
        [--set problem.KEY=VALUE ...]

``--reuse`` measures runs already in ``OUT/ROBOT-seed-N``. Write the printed table into
benchmarks/README.md and docs/humanoid-walk.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

FORWARD = (0.1, 0.2, 0.3)


def evolve(out: Path, robot: str, seed: int, threads: int, sets: list[str]) -> float:
    t0 = time.perf_counter()
    more = [a for s in sets for a in ("--set", s)]
    subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "humanoid-walk",
                    "--robot", robot, "--out", str(out), "--overwrite", "--set",
                    f"run.seed={seed}", "--set", f"problem.threads={threads}", *more,
                    "--quiet"], check=True)
    return time.perf_counter() - t0


def forward(quiet, x, mean, std) -> list[dict]:
    """The forward commands of :data:`FORWARD` alone in ``quiet`` (compare's top-speed test)."""
    from evomotion.studies.humanoid_omniwalk.compare import top_speeds

    tests = {f"{v:g}": (v, 0.0, 0.0) for v in FORWARD}
    return [dict(r, command_mps=r["command"][0])
            for r in top_speeds(quiet, x, mean, std, tests).values()]


def nominal_random(problem, x, mean, std, worlds: int, duration_s: float) -> float:
    from evomotion.studies.humanoid_omniwalk.compare import EVAL_SEED_BASE, _play
    from evomotion.studies.humanoid_omniwalk.problem import OmniWalkProblem

    p = OmniWalkProblem(dataclasses.replace(problem.cfg, duration_s=duration_s, perturb=False,
                                            push_min_ns=0.0, push_max_ns=0.0))
    m = _play(p, x, mean, std, EVAL_SEED_BASE + np.arange(worlds))
    p.sim.close()
    return float(m["survived"].mean())


def measure(folder: Path, worlds: int, duration_s: float) -> dict:
    from evomotion.studies.humanoid_omniwalk.compare import compare, load_run, quiet_problem

    problem, policy, _ = load_run(folder)
    quiet = quiet_problem(problem)
    o = problem.obs_dim
    rows = {"controller": (policy.params, policy.obs_mean, policy.obs_std),
            "engine": (problem.ctl.initial_params(), np.zeros(o), np.ones(o))}
    out: dict = {"robot": problem.robot.name, "period_s": problem.ctl.gait.period_s,
                 "params": int(problem.policy.n_params)}
    for name, (x, mean, std) in rows.items():
        out[name] = {"forward": forward(quiet, x, mean, std),
                     "nominal_random_survival": nominal_random(problem, x, mean, std, worlds,
                                                               duration_s)}
    c = compare(folder, worlds=worlds, duration_s=duration_s)
    for name in rows:
        out[name]["perturbed"] = {k: c[name][k] for k in ("survival", "relative_speed_error",
                                                          "relative_yaw_rate_error")}
        out[name]["top_speeds"] = c[name]["top_speeds"]
    out["push_ns"] = c["push_ns"]
    quiet.sim.close()
    problem.sim.close()
    return out


def _top(t: dict) -> str:
    def v(name: str, key: str, scale: float = 1.0) -> str:
        return f"{scale * t[name][key]:.2f}" + ("*" if t[name]["fell"] else "")

    slowest = "backward" if "backward" in t else "forward_min"  # forward-only ranges
    return (f"{v('forward', 'vx_mps')}, {v(slowest, 'vx_mps')}, {v('left', 'vy_mps')}, "
            f"{t['turn_left']['yaw_rate_dps']:.0f}" + ("*" if t["turn_left"]["fell"] else ""))


def table(results: dict, worlds: int, duration_s: float) -> str:
    lines = ["| robot, seed | controller | " + " | ".join(f"{v:g} m/s fwd" for v in FORWARD)
             + f" | nominal, random cmds ({worlds} x {duration_s:g} s) | perturbed + pushes: "
             "survival | speed error | top: fwd, back, left (m/s), turn (deg/s) | evolve (s) |",
             "|---|---|" + "---|" * (len(FORWARD) + 5)]
    for key, r in results.items():
        for name in ("controller", "engine"):
            c = r[name]
            fw = " | ".join(f"{f['vx_mps']:.2f}" + (" fell" if f["fell"] else "")
                            for f in c["forward"])
            lines.append(f"| {key} | {name} | {fw} | {100 * c['nominal_random_survival']:.0f} % | "
                         f"{100 * c['perturbed']['survival']:.0f} % | "
                         f"{100 * c['perturbed']['relative_speed_error']:.0f} % | "
                         f"{_top(c['top_speeds'])} | "
                         + (f"{r['evolve_s']:.0f} |" if name == "controller" and
                            r.get("evolve_s") else "|"))
    return "\n".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--robots", nargs="+", default=["op3", "dm-humanoid"])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--worlds", type=int, default=20)
    ap.add_argument("--duration", type=float, default=60.0)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--reuse", action="store_true")
    ap.add_argument("--set", dest="sets", action="append", default=[],
                    help="a setting of the evolved runs, KEY=VALUE (repeatable)")
    a = ap.parse_args()
    results = {}
    for robot in a.robots:
        for seed in a.seeds:
            folder = a.out / f"{robot}-seed-{seed}"
            wall = None if a.reuse else evolve(folder, robot, seed, a.threads, a.sets)
            results[f"{robot}, {seed}"] = dict(measure(folder, a.worlds, a.duration),
                                               evolve_s=wall)
    print(json.dumps(results, indent=1))
    print(table(results, a.worlds, a.duration))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
