"""Would a step at once after a push help? An oracle probe (issue 34) on a humanoid-walk run
with capture steps, untrained further: ``--delay`` control steps after each world's push (its
time known: an oracle; a detector would add its own delay) the gait clock jumps to the start
of the next step, so the swinging foot lands now and the other foot lifts, with the run's
capture-step layer placing it (capture-point walk engines end the step when the capture point
leaves the support: walking.md). The clock is otherwise integrated as the simulator's time
(``--delay none``: the run as it is; the probe's clock never jumping is checked against
it). Survival over ``--duration`` s in ``--worlds`` unseen perturbed worlds (``compare``'s
seeds shifted by ``--seed``) with one push of each ``--push`` size, in all and by the push's
direction in the robot's frame (as ``walk_falls.py``).

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

DELAY: list = [0]  # control steps after the push


def next_step(phase: np.ndarray) -> np.ndarray:
    """The gait clock at the start of the next step (the left foot's swing starts at phase 0,
    the right foot's at 1/2): the swinging foot lands now, the other lifts."""
    f = phase % 1.0
    return phase + np.where(f < 0.5, 0.5, 1.0) - f


def clocked_run(ctl, trigger):
    """``Controller.run`` whose gait clock is its own, integrated every control period and
    moved to :func:`next_step` in the rows where ``trigger(worlds, layer)``'s function
    ``(rows, obs, count)`` says (``obs`` with the clock before the jump, ``count`` the control
    steps so far per episode); the run's capture-step layer on top, reading that clock."""
    from evomotion.studies.humanoid_omniwalk.capture_step import CaptureStep

    names = list(ctl.sim.observe.names)
    sin_c, cos_c = names.index("phase:sin"), names.index("phase:cos")
    step = ctl.control_dt / ctl.gait.period_s

    def run(params, mean, std, worlds, nstep, commands):
        n = len(worlds)
        phase, count = np.zeros(n), np.zeros(n, np.int64)
        layer = CaptureStep(ctl, names, n, ctl.capture_gain)
        fire = trigger(worlds, layer)

        def clock(o, rows):
            o[:, sin_c], o[:, cos_c] = np.sin(2 * np.pi * phase[rows]), \
                np.cos(2 * np.pi * phase[rows])

        def policy(rows, obs):
            o = obs.copy()
            clock(o, rows)
            hit = rows[fire(rows, o, count)]
            phase[hit] = next_step(phase[hit])
            clock(o, rows)
            count[rows] += 1
            phase[rows] += step
            return layer(rows, o, ctl.policy.act(params[rows], o, mean[rows], std[rows]))

        return ctl.sim.run(policy, worlds, nstep, commands=commands, initial_state=ctl.state0,
                           record_states=True, record_targets=True)

    return run


def oracle(worlds, layer):
    """Fires ``DELAY[0]`` control steps after each world's push (its time known)."""
    dt = layer.ctl.control_dt
    at = np.array([int(np.ceil(w.push_time_s / dt)) + DELAY[0] for w in worlds])
    return lambda rows, obs, count: count[rows] == at[rows]


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
    plain_run = prob.ctl.run
    plain = {p: prob.play(P, M, S, seeds, p)[1].fell for p in a.push}
    # the probe's own clock, never jumping, is the run as it is (but for the clocks'
    # rounding, which can turn a fall in a world or two)
    prob.ctl.run = clocked_run(prob.ctl, lambda ws, layer: lambda rows, obs, count:
                               np.zeros(len(rows), bool))  # type: ignore[method-assign]
    for p in a.push:
        assert int((prob.play(P, M, S, seeds, p)[1].fell != plain[p]).sum()) <= 2, \
            "the clocks differ"
    head = ["jump (control steps after the push)", "push (N s)", "survival"] + [
        f"pushed {s}" for s in SIDES]
    rows = []
    for d in a.delay:
        if d == "none":  # the run as it is
            prob.ctl.run = plain_run  # type: ignore[method-assign]
        else:
            DELAY[0] = int(d)
            prob.ctl.run = clocked_run(prob.ctl, oracle)  # type: ignore[method-assign]
        for push in a.push:
            ws = prob.worlds(seeds, push)
            res = prob.play(P, M, S, seeds, push)[1]
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
