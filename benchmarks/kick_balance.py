"""The kick with and without balance feedback against pushes (issue 34: "the kick evolved with
the walk's balance feedback"; ``studies/biped_kick/balance.py``): a kick (the shipped default,
or a run's best) played in 100 perturbed worlds (kick_adapt's ranges) with a lateral push
U(-P, P) N s at 25-75 % of the kick, ball offsets U(+-2 cm), aim 0 (the ball at the tolerance
centre, as kick_check), once per pair of gains ``k_pitch,k_roll`` (s; 0,0 the open-loop kick).
Falls, the smallest ZMP margin during the kick (median), within +-10 deg, mean distance.

    python benchmarks/kick_balance.py [RUN] --push 1 2 --gains=0:0,0.05:0.05,-0.05:-0.05
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

import numpy as np

from evomotion.studies.biped_kick.experiment import (
    accuracy,
    kick_draw,
    perturbed_kicks,
    tolerant_offset,
)
from evomotion.studies.biped_kick.play import read_kick
from evomotion.studies.biped_kick.problem import KickConfig, KickProblem


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("run", type=Path, nargs="?", default=None)
    ap.add_argument("--push", type=float, nargs="+", default=[1.0, 2.0])
    ap.add_argument("--gains", default="0:0,0.05:0.05,-0.05:-0.05",
                    help="pairs k_pitch:k_roll (s), comma-separated (--gains=...)")
    ap.add_argument("--worlds", type=int, default=100)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    genome, source = read_kick(args.run)
    gains = [tuple(float(v) for v in g.split(":")) for g in args.gains.split(",")]
    base = KickProblem(KickConfig(nthread=1))
    centre = tolerant_offset(base, genome, 0.0)
    out: dict = {"kick": str(source), "rows": []}
    t0 = time.perf_counter()
    for push in args.push:
        offsets, worlds = kick_draw(base, args.worlds, push_ns=(-push, push))
        for g in gains:
            p = KickProblem(dataclasses.replace(base.cfg, balance_gains=g))
            m = perturbed_kicks(p, genome, offsets + [0, centre], 0.0, worlds)
            out["rows"].append({"push_ns": push, "gains_s": list(g), **accuracy(m),
                                "median_min_margin_mm": float(np.median(m["min_margin_m"]))
                                * 1e3})
    out["wall_s"] = time.perf_counter() - t0
    if args.json:
        print(json.dumps(out, indent=2))
        return
    print(f"kick: {source}; {args.worlds} perturbed worlds per row, lateral push U(-P, P) N s "
          f"at 25-75 % of the kick, ball +-2 cm, aim 0 ({out['wall_s']:.0f} s)")
    print("| push P (N s) | gains k_pitch, k_roll (s) | falls | within +-10 deg | mean distance "
          "(m) | median min ZMP margin (mm) |\n|---|---|---|---|---|---|")
    for r in out["rows"]:
        print(f"| {r['push_ns']:g} | {r['gains_s'][0]:g}, {r['gains_s'][1]:g} | "
              f"{r['fall_rate']:.0%} | {r['within_10deg']:.0%} | {r['mean_distance_m']:.2f} | "
              f"{r['median_min_margin_mm']:.1f} |")


if __name__ == "__main__":
    main()
