"""Scan the walk engine's settings on a robot (issue 34, item 5): for every combination of the
given ``problem`` keys, the fitted engine (the controller's start: the tape, no feedback)
walks 8 s in the nominal world without a push at 0, 0.1, 0.2 and 0.3 m/s forward (ramped over
0.5 s); printed: when each fell (8.0 = stayed up) and its mean speed error (m/s). A setting
whose gait the leg cannot reach prints its one-line error.

    python benchmarks/omniwalk_engine_scan.py dm-humanoid \
        --grid "{'sway_m': [0.01, 0.015], 'step_height_m': [0.005, 0.01], 'period_s': [0.4]}"

What docs/humanoid-walk.md ("Other bipeds") reports for the OP3 and the dm humanoid was
scanned this way (about 100 settings on the dm humanoid).
"""

from __future__ import annotations

import argparse
import ast
import itertools

import numpy as np

SPEEDS = (0.0, 0.1, 0.2, 0.3)


def main() -> int:
    from evomotion.errors import InputError
    from evomotion.studies.humanoid_omniwalk.problem import OmniWalkConfig, OmniWalkProblem

    ap = argparse.ArgumentParser()
    ap.add_argument("robot")
    ap.add_argument("--grid", required=True, help="a Python dict: problem key -> values")
    ap.add_argument("--duration", type=float, default=8.0)
    a = ap.parse_args()
    grid = ast.literal_eval(a.grid)
    for values in itertools.product(*grid.values()):
        kw = dict(zip(grid, values, strict=True))
        try:
            p = OmniWalkProblem(OmniWalkConfig(robot=a.robot, perturb=False, push_max_ns=0.0,
                                               threads=1, duration_s=a.duration, **kw))
            x = p.ctl.initial_params()
        except InputError as e:
            print(kw, "error:", e)
            continue
        n, o = len(SPEEDS), p.obs_dim
        C = int(np.ceil(p.nstep / p.control_steps))
        ramp = np.clip(np.arange(C) * p.ctl.control_dt / 0.5, 0.0, 1.0)[:, None]
        cmds = np.stack([np.tile([v, 0.0, 0.0], (C, 1)) * ramp for v in SPEEDS])
        m, res, _ = p.play(np.tile(x, (n, 1)), np.zeros((n, o)), np.ones((n, o)),
                           np.zeros(n, int), push_ns=0.0, commands=cmds)
        print(kw, "up until (s):", np.round(res.fall_time_s, 1), "speed error (m/s):",
              np.round(m["speed_error_mps"], 3), flush=True)
        p.sim.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
