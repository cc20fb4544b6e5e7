"""The balance task by push direction (issue 33): for each humanoid-balance run folder, its
exported policy and the open-loop stand-still in the run's stance, and the stand-still in the
robot's spec pose (the stance before ``problem.stance_*``), on the same 100 unseen perturbed
worlds as ``evomotion humanoid-balance compare RUN --worlds 100 --push P`` (seed 0): survival
overall and by the push's direction (the NAO faces +x; forward = within 45 deg of +x).
Then the policy's survival by the world's draw: the worlds split at the median of friction
scale, servo latency and the torso's CoM offset along x (+ forward), overall and for the pushes
from the front (the "backward" sector: they push the robot backward).

    python benchmarks/bench_balance.py RUN [RUN ...] [--push 4 3 2] [--worlds 100] [--json]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

import numpy as np

from evomotion.studies.humanoid_balance.compare import eval_seeds, load_run, play_policy
from evomotion.studies.humanoid_balance.episodes import push_range

SECTORS = {"forward": (-45, 45), "left": (45, 135), "right": (-135, -45)}


def sectors(angle_deg: np.ndarray) -> dict[str, np.ndarray]:
    """Each push's sector (forward, left, right as :data:`SECTORS`; backward: the rest)."""
    out = {k: (angle_deg > lo) & (angle_deg <= hi) for k, (lo, hi) in SECTORS.items()}
    out["backward"] = ~(out["forward"] | out["left"] | out["right"])
    return out


def by_direction(survived: np.ndarray, angle_deg: np.ndarray) -> dict[str, float]:
    out = {"all": float(survived.mean())}
    for name, m in sectors(angle_deg).items():
        out[name] = float(survived[m].mean()) if m.any() else float("nan")
    return out


def by_world(survived: np.ndarray, worlds: list, backward: np.ndarray) -> dict[str, dict]:
    """Survival in the worlds below / above the median of each drawn quantity, overall and
    among the backward pushes."""
    values = {
        "friction_scale": [w.params.get("friction_scale", np.nan) for w in worlds],
        "latency_ms": [4.0 * w.latency_steps for w in worlds],
        "torso_com_x_m": [np.ravel(w.params.get("com_offset_m", [np.nan]))[0] for w in worlds],
    }
    out = {}
    for name, v in values.items():
        v = np.asarray(v, dtype=float)
        low = v <= np.median(v)
        out[name] = {"median": float(np.median(v)),
                     "low": float(survived[low].mean()), "high": float(survived[~low].mean()),
                     "backward_low": float(survived[low & backward].mean()),
                     "backward_high": float(survived[~low & backward].mean())}
    return out


def measure(run: Path, push: float, worlds: int) -> dict:
    from evomotion.sim.closed_loop import ClosedLoopSimulator

    problem, policy, _ = load_run(run)
    seeds = eval_seeds(worlds, 0)
    scaled = push_range(problem.robot, push, push)[0]
    vec = np.array([w.push_ns for w in problem.worlds(seeds, scaled)])
    angle = np.degrees(np.arctan2(vec[:, 1], vec[:, 0]))
    out = {"push_ns": push, "worlds": worlds,
           "count": {k: int(m.sum()) for k, m in sectors(angle).items()}}
    worlds = problem.worlds(seeds, scaled)
    for key, zero in (("policy", False), ("stand_still", True)):
        ep = play_policy(problem, policy, seeds, scaled, zero=zero)
        out[key] = by_direction(ep.survived.astype(bool), angle)
        if not zero:
            out["policy_by_world"] = by_world(ep.survived.astype(bool), worlds,
                                              sectors(angle)["backward"])
    # the stand-still in the robot's spec pose, in the same worlds
    from evomotion.sim.robots import load_robot

    spec = load_robot(problem.cfg.robot or "nao")
    threads = getattr(problem.sim, "nthread", 2)  # the CPU simulator's (a Warp run: 2)
    problem.sim.close()
    robot = dataclasses.replace(problem.robot, pose=spec.pose, state0=spec.state0)
    problem.robot = robot
    problem.sim = ClosedLoopSimulator(robot, problem.obs_spec, problem.control_steps, threads)
    ep = play_policy(problem, policy, seeds, scaled, zero=True)
    out["stand_still_spec_pose"] = by_direction(ep.survived.astype(bool), angle)
    problem.sim.close()
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("runs", type=Path, nargs="+")
    ap.add_argument("--push", type=float, nargs="+", default=[4.0])
    ap.add_argument("--worlds", type=int, default=100)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    res = []
    for run in args.runs:
        for push in args.push:
            t0 = time.perf_counter()
            r = measure(run, push, args.worlds)
            r.update(run=str(run), wall_s=time.perf_counter() - t0)
            res.append(r)
    if args.json:
        print(json.dumps(res, indent=1))
        return
    print("| run | push (N s) | controller | survival | forward | backward | left | right |\n"
          "|---|---|---|---|---|---|---|---|")
    for r in res:
        c = r["count"]
        for key, name in (("policy", "evolved policy"), ("stand_still", "stand still, stance"),
                          ("stand_still_spec_pose", "stand still, spec pose")):
            s = r[key]
            print(f"| {r['run']} | {r['push_ns']:g} | {name} | {s['all']:.0%} | "
                  f"{s['forward']:.0%} of {c['forward']} | {s['backward']:.0%} of "
                  f"{c['backward']} | {s['left']:.0%} of {c['left']} | {s['right']:.0%} of "
                  f"{c['right']} |")
    print("\npolicy survival by the world's draw (below / above the median):\n"
          "| run | push (N s) | quantity | median | all: below / above | backward pushes: "
          "below / above |\n|---|---|---|---|---|---|")
    for r in res:
        for name, q in r["policy_by_world"].items():
            print(f"| {r['run']} | {r['push_ns']:g} | {name} | {q['median']:.3g} | "
                  f"{q['low']:.0%} / {q['high']:.0%} | {q['backward_low']:.0%} / "
                  f"{q['backward_high']:.0%} |")


if __name__ == "__main__":
    main()
