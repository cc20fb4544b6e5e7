"""How much does the NAO's own sensing cost a humanoid-walk controller? The simulation gives
the policy (and the capture-step layer's leg odometry) the joints' exact velocities; the NAOqi
runner on a NAO has no velocity sensor and differences the encoder angles over the control
period (``policy_export.APPROXIMATED``), and the encoders are 12-bit magnetic rotary ones
(0.1°: ``2π / 4096`` rad per count; ``../shared/reference/nao-h25.md``). This probe plays the
run's controller with its observation made as the runner makes it:

- ``exact``: the simulator's angles and velocities (the run as trained);
- ``fd``: ``joint_vel = (q_t − q_{t−1}) / control_period`` (0 at the first step);
- ``fd+12bit``: the angles rounded to the encoder's counts first, then differenced.

Each on ``humanoid-walk compare``'s 100 unseen perturbed worlds x 60 s of random commands
with the run's pushes (the same seeds as ``compare``): survival and the tracking errors
(relative over every window, and steady), the controller row only.

    python benchmarks/walk_deployed_sensing.py RUN [RUN ...] [--worlds 100] [--duration 60]
        [--variants exact fd fd+12bit]

``--train`` is not here: ``problem.joint_velocity`` does not exist; the probe tells whether it
would be needed.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from evomotion.studies.humanoid_omniwalk import controller as controller_module  # noqa: E402
from markdown_table import markdown_row, markdown_table  # noqa: E402

ORIGINAL = controller_module.Controller.run
ENCODER_RAD = 2.0 * np.pi / 4096  # one count of a 12-bit encoder
MODE = ["exact"]


def sensed_run(self, params, mean, std, worlds, nstep, commands):
    """``Controller.run`` with the observation made as ``MODE[0]`` says (module doc)."""
    if MODE[0] == "exact":
        return ORIGINAL(self, params, mean, std, worlds, nstep, commands)
    names = list(self.sim.observe.names)
    pos = [i for i, c in enumerate(names) if c.startswith("joint_pos:")]
    vel = [names.index("joint_vel:" + names[i].split(":", 1)[1]) for i in pos]
    last = np.full((len(params), len(pos)), np.nan)
    inner = self.sim.run

    def run(policy, *args, **kwargs):
        def sensed(rows, obs):
            o = obs.copy()
            q = o[:, pos]
            if MODE[0] == "fd+12bit":
                q = np.round(q / ENCODER_RAD) * ENCODER_RAD
                o[:, pos] = q
            prev = last[rows]
            o[:, vel] = np.where(np.isnan(prev), 0.0, (q - prev) / self.control_dt)
            last[rows] = q
            return policy(rows, o)

        return inner(sensed, *args, **kwargs)

    self.sim.run = run
    try:
        return ORIGINAL(self, params, mean, std, worlds, nstep, commands)
    finally:
        del self.sim.run


def tracking_cells(s: dict) -> list[str]:
    """``compare``'s speed and yaw-rate errors of summary ``s``: "every window / steady"."""
    return [f"{s[f'relative_{q}_error']:.1%} / {s[f'steady_relative_{q}_error']:.1%}"
            for q in ("speed", "yaw_rate")]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--variants", nargs="+", default=["exact", "fd", "fd+12bit"],
                    choices=["exact", "fd", "fd+12bit"])
    ap.add_argument("--worlds", type=int, default=100)
    ap.add_argument("--duration", type=float, default=60.0)
    a = ap.parse_args()
    from evomotion.studies.humanoid_omniwalk.compare import (
        EVAL_SEED_BASE,
        _play,
        _summary,
        load_run,
    )

    controller_module.Controller.run = sensed_run  # type: ignore[method-assign]
    head = ["run", "sensing", "survival", "speed error: every window / steady",
            "yaw-rate error: every window / steady"]
    rows = []
    for run in a.runs:
        problem, pol, _ = load_run(run, a.duration)
        seeds = EVAL_SEED_BASE + np.arange(a.worlds)
        for mode in a.variants:
            MODE[0] = mode
            s = _summary(_play(problem, pol.params, pol.obs_mean, pol.obs_std, seeds))
            rows.append([run, mode, f"{s['survival']:.0%}", *tracking_cells(s)])
            print(markdown_row(rows[-1]), flush=True)
        problem.sim.close()
    print(f"\n{a.worlds} worlds x {a.duration:g} s, the run's pushes, random commands\n")
    print(markdown_table(head, rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
