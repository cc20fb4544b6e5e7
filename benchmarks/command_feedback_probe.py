"""Probe (issue 34, walk against pushes): would a capture-style command feedback help the walk
controller? The shipped controller (``studies/biped_kick/default_walk``), untrained further,
with its command offset by ``k * (gravity direction - its standing mean)`` (x and y of the IMU's
gravity in the torso frame: lean forward -> walk forward) before its command-modulated tape
reads it, so the step length and width follow the lean (a phase-dependent correction the
linear joint feedback cannot express). Survival over ``--duration`` s in ``--worlds`` unseen
perturbed worlds (the omniwalk compare's seeds), standing still and under the random command
schedule, with every push ``--push`` N s.

    python benchmarks/command_feedback_probe.py --duration 6 --worlds 20 --push 3 5
"""

from __future__ import annotations

import argparse
import dataclasses
from importlib.resources import files

import numpy as np

from evomotion.core.policies.export import read_policy_npz
from evomotion.core.policies.structured import StructuredSpec
from evomotion.studies.humanoid_omniwalk.compare import EVAL_SEED_BASE
from evomotion.studies.humanoid_omniwalk.problem import OmniWalkConfig, OmniWalkProblem

GAINS = [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1), (2, 2), (-2, -2), (2, -2), (-2, 2)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=6.0)
    ap.add_argument("--worlds", type=int, default=20)
    ap.add_argument("--push", type=float, nargs="+", default=[3.0, 5.0])
    a = ap.parse_args()
    pol = read_policy_npz(files("evomotion.studies.biped_kick") / "default_walk" / "policy.npz")
    prob = OmniWalkProblem(dataclasses.replace(OmniWalkConfig(), duration_s=a.duration,
                                               threads=1))
    names = list(prob.ctl.sim.observe.names)
    grav = [names.index("gravity:x"), names.index("gravity:y")]
    cmd = [names.index("command:0"), names.index("command:1")]
    gain = np.zeros(2)
    plain = StructuredSpec.act

    def act(self, params, obs, mean, std):  # the probe's only change: the command offset
        m = mean if mean.ndim == 1 else mean[0]
        o = obs.copy()
        o[:, cmd] += gain * (obs[:, grav] - m[grav])
        return plain(self, params, o, mean, std)

    StructuredSpec.act = act  # type: ignore[method-assign]
    seeds = EVAL_SEED_BASE + np.arange(a.worlds)
    n = len(seeds)
    P, M, S = (np.tile(v, (n, 1)) for v in (pol.params, pol.obs_mean, pol.obs_std))
    stand = np.zeros((n, int(np.ceil(prob.nstep / prob.control_steps)), 3))
    print("| push (N s) | k_x | k_y | survival standing | survival random commands |")
    print("|---|---|---|---|---|")
    for push in a.push:
        for kx, ky in GAINS:
            gain[:] = kx, ky
            up = [float(np.mean(~prob.play(P, M, S, seeds, push, c)[1].fell))
                  for c in (stand, None)]
            print(f"| {push:g} | {kx:+g} | {ky:+g} | {up[0]:.0%} | {up[1]:.0%} |", flush=True)


if __name__ == "__main__":
    main()
