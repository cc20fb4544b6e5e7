"""humanoid-repertoire figures (issue 14) from a finished run folder.

1. Filled cells, and the share whose ``.motion``, replayed as ``evomotion replay FILE --hold
   2`` does (``sim/robots/nao/replay.simulate_motion``, the same code), reproduces the indexed
   behaviour within 2 cm (dx and dy) and 5 degrees and does not fall.
2. ``pick`` for ten requests spread over the archive's box: the picked cell's replayed
   behaviour against the request (error in cm / degrees).
3. ``walk-to`` for five target poses 0.3-1 m away: final position and heading error, falls.

    python benchmarks/repertoire_check.py RUN_DIR [--json]
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from evomotion.sim.robots.nao.replay import simulate_motion
from evomotion.studies.humanoid_repertoire.artifacts import read_cell, read_index
from evomotion.studies.humanoid_repertoire.step_planning import pick, walk_to

PICKS = [(0.10, 0.0, 0.0), (0.05, 0.0, 0.0), (-0.06, 0.0, 0.0), (0.0, 0.05, 0.0),
         (0.0, -0.05, 0.0), (0.0, 0.0, 30.0), (0.0, 0.0, -30.0), (0.06, 0.04, 15.0),
         (0.08, -0.03, -20.0), (-0.04, 0.03, 10.0)]
TARGETS = [(0.3, 0.0, 0.0), (0.5, 0.2, 0.0), (0.6, -0.3, -30.0), (0.8, 0.0, 45.0),
           (0.2, 0.6, 90.0)]


def replayed(motion, hold_s: float) -> tuple[np.ndarray, bool]:
    s = simulate_motion(motion, hold_s=hold_s)["summary"]
    return np.array([*s["displacement_m"], math.degrees(s["heading_change_rad"])]), s["fell"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run", type=Path)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    folder, index = read_index(a.run)
    hold = float(index.get("hold_s", 2.0))
    entries = index["entries"]
    t0 = time.perf_counter()
    ok = fell = 0
    worst = np.zeros(3)
    for e in entries:
        got, f = replayed(read_cell(folder, e), hold)
        want = np.array([e["measured"]["dx_m"], e["measured"]["dy_m"],
                         e["measured"]["dtheta_deg"]])
        err = np.abs(got - want)
        worst = np.maximum(worst, err)
        fell += f
        ok += (not f) and err[0] <= 0.02 and err[1] <= 0.02 and err[2] <= 5.0
    out = {"cells": index["cells"], "filled": len(entries),
           "reproduced": ok, "reproduced_share": ok / len(entries), "fell_on_replay": fell,
           "worst_replay_error": {"dx_m": worst[0], "dy_m": worst[1], "dtheta_deg": worst[2]},
           "replay_s": time.perf_counter() - t0, "pick": [], "walk_to": []}
    from evomotion.sim.motion import read_motion

    for req in PICKS:
        r = pick(a.run, *req)
        got, f = replayed(read_motion(r["file"]), hold)
        out["pick"].append({"requested": req, "cell": r["cell"],
                            "replayed": [round(float(v), 4) for v in got], "fell": f,
                            "error_cm": float(100 * np.hypot(*(got[:2] - req[:2]))),
                            "error_deg": float(abs(got[2] - req[2]))})
    for x, y, th in TARGETS:
        w = walk_to(a.run, x, y, th, out=a.run / f"walk_to_{x}_{y}_{th}.motion")
        out["walk_to"].append({k: w[k] for k in ("target", "steps", "reached",
                                                 "position_error_m", "heading_error_deg",
                                                 "fell", "duration_s")})
    if a.json:
        print(json.dumps(out, indent=1))
        return
    print(f"filled {out['filled']} of {out['cells']} cells; replay reproduces (2 cm, 5 deg, "
          f"no fall) {ok} = {100 * ok / len(entries):.1f} %; fell on replay {fell}; worst "
          f"error {worst[0] * 100:.2f} / {worst[1] * 100:.2f} cm, {worst[2]:.2f} deg")
    print("pick: requested (dx m, dy m, dtheta deg) -> replayed; error")
    for p in out["pick"]:
        print(f"  {p['requested']} -> {p['replayed']} {'FELL' if p['fell'] else ''} "
              f"{p['error_cm']:.1f} cm, {p['error_deg']:.1f} deg")
    print("walk-to: target -> reached; steps; error; fell")
    for w in out["walk_to"]:
        r = w["reached"]
        print(f"  {tuple(w['target'].values())} -> ({r['x_m']:+.3f}, {r['y_m']:+.3f}, "
              f"{r['theta_deg']:+.1f}); {w['steps']} steps, {w['duration_s']:.1f} s; "
              f"{w['position_error_m'] * 100:.1f} cm, {w['heading_error_deg']:.1f} deg; "
              f"{'FELL' if w['fell'] else 'up'}")


if __name__ == "__main__":
    main()
