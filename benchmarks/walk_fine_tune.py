"""Walk controllers of one robot side by side on the same commands: a run and the runs
started from it (``problem.start_policy``, a curriculum or a fine-tune).

Every controller is played by the problem of the LAST run given (so on its command ranges and
worlds; the controllers must fit it, as a start policy must):

- **each command alone** (compare's top-speed test: nominal world, no push, ramped over the
  run's ramp, 10 s, the walked velocity and yaw rate over the last half): forward 0.1 / 0.2 /
  0.3 m/s, sideways ±``--vy``, turning ±``--yaw``, and the zero command;
- **random commands**: ``--worlds`` schedules of ``--duration`` s of the last run's random
  commands in the nominal world without pushes: survival, and the relative speed and yaw-rate
  errors over every window (compare's measure).

    python benchmarks/walk_fine_tune.py RUN_A RUN_B [--vy 0.1] [--yaw 0.5] [--worlds 20] \
        [--duration 60]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

from evomotion.errors import InputError


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("runs", type=Path, nargs="+")
    ap.add_argument("--vy", type=float, default=0.1)
    ap.add_argument("--yaw", type=float, default=0.5)
    ap.add_argument("--worlds", type=int, default=20)
    ap.add_argument("--duration", type=float, default=60.0)
    a = ap.parse_args()
    if not 1 <= a.worlds <= 10000 or not 0.5 <= a.duration <= 600:
        ap.error("--worlds must be 1 to 10000 and --duration 0.5 to 600 s")
    if not (0 <= a.vy <= 2 and 0 <= a.yaw <= 10):
        ap.error("--vy must be 0 to 2 m/s and --yaw 0 to 10 rad/s")
    try:
        return _table(a)
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2


def _table(a: argparse.Namespace) -> int:
    from evomotion.studies.humanoid_omniwalk.compare import (
        EVAL_SEED_BASE,
        _pct,
        _play,
        _summary,
        load_run,
        quiet_problem,
        top_speeds,
    )
    from evomotion.studies.humanoid_omniwalk.problem import OmniWalkProblem
    from evomotion.studies.policy_start import check_same_controller

    loaded = [load_run(r) for r in a.runs]
    problem = loaded[-1][0]
    for run, (_, policy, _) in zip(a.runs, loaded, strict=True):
        check_same_controller(run, policy.spec, problem.policy, "RUN")  # one line if not
    quiet = quiet_problem(problem)
    nominal = OmniWalkProblem(dataclasses.replace(problem.cfg, duration_s=a.duration,
                                                  perturb=False, push_min_ns=0.0,
                                                  push_max_ns=0.0))
    tests = {"fwd 0.1": (0.1, 0, 0), "fwd 0.2": (0.2, 0, 0), "fwd 0.3": (0.3, 0, 0),
             f"left {a.vy:g}": (0, a.vy, 0), f"right {a.vy:g}": (0, -a.vy, 0),
             f"turn left {a.yaw:g}": (0, 0, a.yaw), f"turn right {a.yaw:g}": (0, 0, -a.yaw),
             "stand": (0, 0, 0)}
    head = ["run"] + list(tests) + ["random cmds: survival", "speed error", "yaw-rate error"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    seeds = EVAL_SEED_BASE + np.arange(a.worlds)
    for run, (_, policy, _) in zip(a.runs, loaded, strict=True):
        x, mean, std = policy.params, policy.obs_mean, policy.obs_std
        top = top_speeds(quiet, x, mean, std, tests)
        cells = []
        for name, (vx, vy, w) in tests.items():
            r = top[name]
            got = (f"{r['yaw_rate_dps']:.0f}°/s" if w else
                   f"{r['vy_mps']:+.2f}" if vy else f"{r['vx_mps']:+.2f}")
            cells.append(got + (" fell" if r["fell"] else ""))
        s = _summary(_play(nominal, x, mean, std, seeds))
        print(f"| {run} | " + " | ".join(cells) + f" | {100 * s['survival']:.0f} % | "
              f"{_pct(s['relative_speed_error'])} | {_pct(s['relative_yaw_rate_error'])} |")
    for p in (quiet, nominal, *(lo[0] for lo in loaded)):
        p.sim.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
