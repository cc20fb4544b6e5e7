"""biped-kick figures (issues 15, 34) from a finished run folder.

1. ``evomotion replay RUN/best.motion`` (the kick alone, no ball, the same code): fell or not.
2. Straight kicks: 100 kicks from ball positions perturbed by U(+-2 cm) on the nominal
   (calibrated) carpet: mean and maximum distance, falls. As ``play`` places it, the ball's
   nominal place is the centre of the kick's tolerance to lateral placement errors at that aim
   (``experiment.tolerant_offset``, printed).
3. Aimed kicks: 100 kicks at each of -30, -20, -10, 0, +10, +20, +30 deg from ball positions
   perturbed by U(+-2 cm), each in its own perturbed world (``experiment.kick_draw``:
   friction x0.5-1.4, masses +-10 %, torso CoM +-2 cm, motors +-10 %, latency 0-40 ms; the
   ball's carpet nominal): median absolute angle error, share within +-10 deg, fall rate,
   mean distance along the aim.
4. ``play`` from five ball positions 1-2 m from the robot (at the origin, facing +x), target the
   goal centre (4.5, 0): ball-at-rest error to the target line, falls, total time; with the
   walking model, and with ``--walk REPERTOIRE_RUN`` also walking with that repertoire's steps
   in the same simulation. ``--videos DIR`` writes one MP4 per play.

    python benchmarks/kick_check.py RUN_DIR [--walk REPERTOIRE_RUN] [--videos DIR] [--json]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from evomotion.sim.motion import read_motion
from evomotion.sim.robots.nao.replay import simulate_motion
from evomotion.studies.biped_kick.experiment import (
    accuracy,
    kick_draw,
    perturbed_kicks,
    summary,
    tolerant_offset,
)
from evomotion.studies.biped_kick.play import play, read_kick
from evomotion.studies.biped_kick.problem import KickConfig, KickProblem

BALLS = [(1.0, 0.3), (1.5, -0.5), (1.2, 1.0), (2.0, 0.0), (0.8, -1.2)]
TARGET = (4.5, 0.0)
AIMS_DEG = (-30, -20, -10, 0, 10, 20, 30)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("run", type=Path)
    ap.add_argument("--walk", type=Path, default=None)
    ap.add_argument("--videos", type=Path, default=None)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    out: dict = {}
    rep = simulate_motion(read_motion(args.run / "best.motion"), hold_s=1.0)["summary"]
    out["replay"] = {"fell": rep["fell"], "displacement_m": rep["displacement_m"]}
    genome, _ = read_kick(args.run)
    problem = KickProblem(KickConfig())
    offsets, worlds = kick_draw(problem)
    centre = {a: tolerant_offset(problem, genome, a) for a in (0, *AIMS_DEG)}
    out["tolerant_offset_m"] = {f"{a:+d}": v for a, v in centre.items()}
    out["straight"] = summary(perturbed_kicks(problem, genome, offsets + [0, centre[0]], 0.0))
    out["aimed"] = {f"{a:+d}": accuracy(perturbed_kicks(problem, genome, offsets + [0, centre[a]],
                                                        a, worlds))
                    for a in AIMS_DEG}
    walks = [("model", None)] + ([("repertoire", args.walk)] if args.walk else [])
    out["play"] = []
    for label, rep_dir in walks:
        for i, ball in enumerate(BALLS):
            video = None
            if args.videos:
                args.videos.mkdir(parents=True, exist_ok=True)
                video = args.videos / f"play_{label}_{i}.mp4"
            t0 = time.perf_counter()
            r = play(problem, genome, np.zeros(3), np.array(ball), np.array(TARGET), video,
                     repertoire=rep_dir)
            r.update(walk_kind=label, ball=list(ball), wall_s=time.perf_counter() - t0)
            out["play"].append(r)
    if args.json:
        print(json.dumps(out, indent=2))
        return
    print(f"replay best.motion (no ball): {'FELL' if out['replay']['fell'] else 'stayed up'}")
    st = out["straight"]
    print("ball placed at the tolerance centre (cm, + left) per aim: " + ", ".join(
        f"{a}: {100 * v:+.1f}" for a, v in out["tolerant_offset_m"].items()))
    print(f"straight, 100 kicks (+-2 cm): mean {st['mean_distance_m']:.2f} m, max "
          f"{st['max_distance_m']:.2f} m, falls {st['fall_rate']:.0%}")
    print("\naimed, 100 kicks each (+-2 cm, perturbed worlds)")
    print("| aim (deg) | median abs. angle error (deg) | within +-10 deg | falls | "
          "mean distance (m) |\n|---|---|---|---|---|")
    for a, s in out["aimed"].items():
        print(f"| {a} | {s['median_abs_angle_error_deg']:.1f} | {s['within_10deg']:.0%} | "
              f"{s['fall_rate']:.0%} | {s['mean_distance_m']:.2f} |")
    print("\n| walk | ball (m) | aim (deg) | ball at rest (m) | error to target line (m) | "
          "fell | total time (s) | walk steps | placement error (cm) |\n"
          "|---|---|---|---|---|---|---|---|---|")
    for r in out["play"]:
        print(f"| {r['walk_kind']} | ({r['ball'][0]:.1f}, {r['ball'][1]:.1f}) | "
              f"{r['aim_deg']:+.0f} | ({r['ball_rest_m'][0]:.2f}, {r['ball_rest_m'][1]:.2f}) | "
              f"{r['target_error_m']:.2f} | {'yes' if r['fell'] else 'no'} | {r['time_s']:.1f} | "
              f"{r.get('walk_steps', '-')} | {100 * r['ball_placement_error_m']:.1f} |")


if __name__ == "__main__":
    main()
