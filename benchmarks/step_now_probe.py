"""Would a step at once after a push help? An oracle probe (issue 34) on a humanoid-walk run
with capture steps, untrained further: ``--delay`` control steps after each world's push (its
time known: an oracle; a detector would add its own delay) the gait clock jumps to the start
of the next step, so the swinging foot lands now and the other foot lifts, with the run's
capture-step layer placing it (capture-point walk engines end the step when the capture point
leaves the support: walking.md). The clock is otherwise integrated as the simulator's time
(``--delay none``: never jumps, the run as it is, checked against the plain play). Survival
over ``--duration`` s in ``--worlds`` unseen perturbed worlds (``compare``'s seeds shifted by
``--seed``) with one push of each ``--push`` size, in all and by the push's direction in the
robot's frame (as ``walk_falls.py``).

    python benchmarks/step_now_probe.py RUN [--delay none 0 2 5] [--push 3 4]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from markdown_table import markdown_row, markdown_table  # noqa: E402
from walk_falls import SIDES, push_sides, side_cells  # noqa: E402

DELAY: list = [None]  # control steps after the push, or None: never


def jumping_run(ctl):
    """``Controller.run`` with the oracle's clock (module doc) and the run's layer on top."""
    from evomotion.studies.humanoid_omniwalk.capture_step import CaptureStep

    names = list(ctl.sim.observe.names)
    sin_c, cos_c = names.index("phase:sin"), names.index("phase:cos")
    step = ctl.control_dt / ctl.gait.period_s

    def run(params, mean, std, worlds, nstep, commands):
        n = len(worlds)
        phase, count = np.zeros(n), np.zeros(n, np.int64)
        at = np.array([-1 if DELAY[0] is None else
                       int(np.ceil(w.push_time_s / ctl.control_dt)) + DELAY[0] for w in worlds])
        layer = CaptureStep(ctl, names, n, ctl.capture_gain)

        def policy(rows, obs):
            o = obs.copy()
            if DELAY[0] is not None:
                hit = rows[count[rows] == at[rows]]
                f = phase[hit] % 1.0
                phase[hit] += np.where(f < 0.5, 0.5, 1.0) - f  # the next step starts now
                o[:, sin_c] = np.sin(2 * np.pi * phase[rows])
                o[:, cos_c] = np.cos(2 * np.pi * phase[rows])
            count[rows] += 1
            phase[rows] += step
            return layer(rows, o, ctl.policy.act(params[rows], o, mean[rows], std[rows]))

        return ctl.sim.run(policy, worlds, nstep, commands=commands, initial_state=ctl.state0,
                           record_states=True, record_targets=True)

    return run


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run")
    ap.add_argument("--delay", nargs="+", default=["none", "0", "2", "5"])
    ap.add_argument("--push", type=float, nargs="+", default=[3.0, 4.0])
    ap.add_argument("--worlds", type=int, default=100)
    ap.add_argument("--duration", type=float, default=6.0)
    ap.add_argument("--seed", type=int, default=7)
    a = ap.parse_args()
    from evomotion.studies.humanoid_omniwalk.commands import heading_at
    from evomotion.studies.humanoid_omniwalk.compare import EVAL_SEED_BASE, MAX_WORLDS, load_run

    prob, pol, _ = load_run(a.run, a.duration)
    if not prob.ctl.capture_gain:
        ap.error(f"{a.run}: no capture steps (problem.capture_gain 0)")
    seeds = EVAL_SEED_BASE + a.seed * MAX_WORLDS + np.arange(a.worlds)
    n, dt = len(seeds), prob.ctl.control_dt
    P, M, S = (np.tile(v, (n, 1)) for v in (pol.params, pol.obs_mean, pol.obs_std))
    plain = {p: prob.play(P, M, S, seeds, p)[1].fell for p in a.push}
    prob.ctl.run = jumping_run(prob.ctl)  # type: ignore[method-assign]
    head = ["jump (control steps after the push)", "push (N s)", "survival"] + [
        f"pushed {s}" for s in SIDES]
    rows = []
    for d in a.delay:
        DELAY[0] = None if d == "none" else int(d)
        for push in a.push:
            ws = prob.worlds(seeds, push)
            res = prob.play(P, M, S, seeds, push)[1]
            if DELAY[0] is None:  # the probe's own clock, never jumping: the run as it is
                assert int((res.fell != plain[push]).sum()) <= 2, "the clocks differ"
            up = ~res.fell
            side = push_sides(ws, heading_at(res.torso, np.array([w.push_time_s for w in ws]),
                                             dt))
            rows.append([d, f"{push:g}", f"{up.mean():.0%}", *side_cells(up, side)])
            print(markdown_row(rows[-1]), flush=True)
    print(f"\n{a.run}: {n} worlds x {a.duration:g} s, one push each, random commands\n")
    print(markdown_table(head, rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
