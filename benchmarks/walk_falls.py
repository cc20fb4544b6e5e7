"""Where a humanoid-walk controller falls: its run's pushes, no push at all, and by the push's
size and its direction in the robot's own frame at the moment of the push.

    python benchmarks/walk_falls.py RUN [RUN ...] [--worlds 100] [--duration 60] [--seed 0]

The worlds and command schedules are ``humanoid-walk compare``'s (the same seeds, so the
"run's pushes" row is compare's survival); "no push" plays the same worlds and schedules with
every push 0 N s; ``--pushes MIN MAX`` plays another push range than the run's (a run
trained with other pushes, measured on the default's ``0 5``). A fall "after the push" is
one within 2 s of it. Directions: the push's horizontal direction against the torso's
heading at the push (within 45° of forward, of backward, to the left, to the right).
Push sizes are the worlds' own (for another robot than the NAO, already scaled by its mass:
``episode_worlds.push_range``). Output: one markdown table per run, then JSON with
``--json``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys

import numpy as np

BINS = ((0.0, 2.0), (2.0, 3.0), (3.0, 4.0), (4.0, float("inf")))
SIDES = ("forward", "backward", "left", "right")


def _episodes(problem, policy, seeds: np.ndarray, push_t: np.ndarray, push_ns: float | None,
              batch: int = 20):
    """(survived[n], time up (s)[n], heading (rad)[n] at each world's push time ``push_t``)."""
    from evomotion.studies.humanoid_omniwalk.commands import heading_at

    up, t_up, heading = [], [], []
    for a in range(0, len(seeds), batch):
        s = seeds[a:a + batch]
        n = len(s)
        m, res, _ = problem.play(np.tile(policy.params, (n, 1)), np.tile(policy.obs_mean, (n, 1)),
                                 np.tile(policy.obs_std, (n, 1)), s, push_ns)
        heading.append(heading_at(res.torso, push_t[a:a + n], problem.ctl.control_dt))
        up.append(m["survived"] >= 1)
        t_up.append(m["time_up_s"])
    return np.concatenate(up), np.concatenate(t_up), np.concatenate(heading)


def push_sides(ws: list, heading: np.ndarray) -> np.ndarray:
    """Each world's push direction against the torso's ``heading`` (rad) at the push: 0
    forward, 1 backward (within 45°), 2 left, 3 right (:data:`SIDES`)."""
    vec = np.array([w.push_ns[:2] for w in ws], float)
    rel = np.angle(np.exp(1j * (np.arctan2(vec[:, 1], vec[:, 0]) - heading)))
    return np.select([np.abs(rel) <= np.pi / 4, np.abs(rel) >= 3 * np.pi / 4, rel > 0],
                     [0, 1, 2], 3)


def side_cells(up: np.ndarray, side: np.ndarray) -> list[str]:
    """Survival "NN% (worlds)" pushed forward, backward, left, right."""
    return [f"{up[side == i].mean():.0%} ({(side == i).sum()})" if (side == i).any() else "-"
            for i in range(len(SIDES))]


def measure(run: str, worlds: int, duration_s: float, seed: int,
            pushes: tuple[float, float] | None = None) -> dict:
    from evomotion.studies.humanoid_omniwalk.compare import EVAL_SEED_BASE, MAX_WORLDS, load_run
    from evomotion.studies.humanoid_omniwalk.problem import OmniWalkProblem

    problem, policy, folder = load_run(run, duration_s)
    if pushes is not None:  # another range than the run trained with (the default's: 0 5)
        problem.sim.close()
        problem = OmniWalkProblem(dataclasses.replace(problem.cfg, push_min_ns=pushes[0],
                                                      push_max_ns=pushes[1]))
    seeds = EVAL_SEED_BASE + seed * MAX_WORLDS + np.arange(worlds)
    ws = problem.worlds(seeds, None)
    when = np.array([w.push_time_s for w in ws])
    up, t_up, heading = _episodes(problem, policy, seeds, when, None)
    up0, _, _ = _episodes(problem, policy, seeds, when, 0.0)
    problem.sim.close()
    mag = np.array([w.params["push_magnitude_ns"] for w in ws])
    side = push_sides(ws, heading)
    fell = ~up
    out = {"run": str(folder), "worlds": worlds, "duration_s": duration_s,
           "survival": float(up.mean()), "survival_no_push": float(up0.mean()),
           "falls_within_2s_of_push": int((fell & (t_up >= when) & (t_up < when + 2)).sum()),
           "falls_before_push": int((fell & (t_up < when)).sum()), "falls": int(fell.sum()),
           "by_size": {}, "by_side": {}}
    for lo, hi in BINS:
        s = (mag >= lo) & (mag < hi)
        name = f"{lo:g}-{hi:g}" if hi < float("inf") else f"{lo:g}+"
        out["by_size"][name] = [int(s.sum()), float(up[s].mean()) if s.any() else float("nan")]
    big = mag >= 3.0
    for i, name in enumerate(SIDES):
        s = big & (side == i)
        out["by_side"][name] = [int(s.sum()), float(up[s].mean()) if s.any() else float("nan")]
    return out


def table(r: dict) -> str:
    def share(v) -> str:  # (count, survival); "– of 0" where no world had such a push
        return f"{100 * v[1]:.0f} % of {v[0]}" if v[0] else "– of 0"

    sizes = " / ".join(share(v) for v in r["by_size"].values())
    sides = " / ".join(share(v) for v in r["by_side"].values())
    return "\n".join([
        f"{r['run']}: {r['worlds']} worlds x {r['duration_s']:g} s", "",
        "| run's pushes | no push | falls within 2 s of the push / before it / all | "
        f"by push {' / '.join(r['by_size'])} N s | pushes ≥ 3 N s from behind / the front / "
        "right / left (pushed forward / backward / left / right) |",
        "|---|---|---|---|---|",
        f"| {100 * r['survival']:.0f} % | {100 * r['survival_no_push']:.0f} % | "
        f"{r['falls_within_2s_of_push']} / {r['falls_before_push']} / {r['falls']} | {sizes} | "
        f"{sides} |"])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--worlds", type=int, default=100)
    ap.add_argument("--duration", type=float, default=60.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--pushes", type=float, nargs=2, metavar=("MIN", "MAX"),
                    help="push range (N s) instead of the run's own")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    if a.worlds < 1 or a.duration <= 0 or a.seed < 0 or (a.pushes and not
                                                         0 <= a.pushes[0] <= a.pushes[1]):
        ap.error("expected --worlds >= 1, --duration > 0, --seed >= 0 and 0 <= MIN <= MAX")
    res = [measure(r, a.worlds, a.duration, a.seed, a.pushes and tuple(a.pushes)) for r in a.runs]
    for r in res:
        print(table(r), "\n")
    if a.json:
        print(json.dumps(res, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
