"""Probe (issue 34, walk against pushes): would quicker steps after a push help the walk
controller? An evolved controller (``RUN``'s ``policy.npz``), untrained further, whose gait
clock runs faster while the torso leans or tips more than it does walking: its phase is
integrated every control period at ``1 + k * clip((s - s0) / 3, 0, 1)`` times the nominal
rate, with ``s`` the IMU's deviation from the walk's statistics (the norm of the normalised
gravity x, y and gyro x, y: "how hard it was pushed") and ``s0`` a threshold, so a large push
gives steps up to ``1 + k`` times quicker (capture-point walk engines shorten or end the step
when the capture point leaves the support; walking.md). ``k = 0`` is the controller as it
is; the script checks that the plain run and the probe's own clock with a trigger never
reached (``s0`` huge) give the same falls, returns and torso paths (to 1e-9: the clock
integrated in steps against the state's time). Survival over ``--duration`` s in
``--worlds`` unseen perturbed worlds (the compare's seeds) under their random command
schedules, with every push ``--push`` N s. A run with capture steps (``problem.capture_gain``)
plays its layer on top, reading the probe's clock (2026-12-07; the second check above is then
left out: the layer turns the clocks' rounding into a different fall in a world or two).

    python benchmarks/step_timing_probe.py RUN --duration 8 --worlds 40 --push 3 4 5
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from evomotion.core.policies.export import read_policy_npz  # noqa: E402
from evomotion.run.config import config_from_dict, config_from_run_dir  # noqa: E402
from evomotion.studies import get_study  # noqa: E402
from evomotion.studies.humanoid_omniwalk.compare import EVAL_SEED_BASE  # noqa: E402
from evomotion.studies.humanoid_omniwalk.problem import OmniWalkProblem  # noqa: E402

SETTINGS = [(0.0, 2.0), (0.5, 2.0), (1.0, 2.0), (0.5, 1.0), (1.0, 1.0), (0.5, 3.0),
            (1.0, 3.0), (-0.3, 2.0)]


def timed_run(ctl, gain: list[float], names: list[str]):
    """``Controller.run`` with the gait clock integrated at the probe's rate."""
    sin_c, cos_c = names.index("phase:sin"), names.index("phase:cos")
    push_c = [names.index(c) for c in ("gravity:x", "gravity:y", "gyro:x", "gyro:y")]
    step = ctl.control_dt / ctl.gait.period_s

    def run(params, mean, std, worlds, nstep, commands):
        from evomotion.studies.humanoid_omniwalk.capture_step import CaptureStep

        phase = np.zeros(len(worlds))
        spec = ctl.policy
        layer = (CaptureStep(ctl, names, len(params), ctl.capture_gain)
                 if ctl.capture_gain else None)

        def policy(rows, obs):
            k, s0 = gain
            o = obs.copy()
            if k:
                o[:, sin_c] = np.sin(2 * np.pi * phase[rows])
                o[:, cos_c] = np.cos(2 * np.pi * phase[rows])
                z = (obs[:, push_c] - mean[rows][:, push_c]) / std[rows][:, push_c]
                s = np.sqrt((z ** 2).sum(axis=1))
                phase[rows] += step * (1.0 + k * np.clip((s - s0) / 3.0, 0.0, 1.0))
            act = spec.act(params[rows], o, mean[rows], std[rows])
            return act if layer is None else layer(rows, o, act)

        return ctl.sim.run(policy, worlds, nstep, commands=commands,
                           initial_state=ctl.state0, record_states=True, record_targets=True)

    return run


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", type=Path, help="a humanoid-walk run folder")
    ap.add_argument("--duration", type=float, default=8.0)
    ap.add_argument("--worlds", type=int, default=40)
    ap.add_argument("--push", type=float, nargs="+", default=[3.0, 4.0, 5.0])
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    study, raw = config_from_run_dir(a.run)
    raw["problem"].update(duration_s=a.duration, threads=a.threads)
    cfg = config_from_dict(get_study(study), raw)
    prob = OmniWalkProblem(cfg.problem)
    pol = read_policy_npz(a.run / "policy.npz")
    names = list(prob.ctl.sim.observe.names)
    seeds = EVAL_SEED_BASE + np.arange(a.worlds)
    n = len(seeds)
    P, M, S = (np.tile(v, (n, 1)) for v in (pol.params, pol.obs_mean, pol.obs_std))
    gain = [0.0, 2.0]
    m0, res0, _ = prob.play(P, M, S, seeds, a.push[0])
    prob.ctl.run = timed_run(prob.ctl, gain, names)  # type: ignore[method-assign]
    checks = ((0.0, 2.0), (1.0, 1e9)) if not prob.ctl.capture_gain else ((0.0, 2.0),)
    for k, s0 in checks:  # as it is; the probe's clock, never triggered
        gain[:] = k, s0
        m1, res1, _ = prob.play(P, M, S, seeds, a.push[0])
        assert np.array_equal(res0.fall_step, res1.fall_step), (k, s0)
        np.testing.assert_allclose(m1["return"], m0["return"], rtol=0, atol=1e-9)
        np.testing.assert_allclose(res1.torso, res0.torso, rtol=0, atol=1e-9)
    print(f"{a.run}: {n} worlds, {a.duration:g} s, random commands")
    print("| push (N s) | k | s0 | survival | speed error (m/s) |")
    print("|---|---|---|---|---|")
    for push in a.push:
        for k, s0 in SETTINGS:
            gain[:] = k, s0
            m, res, _ = prob.play(P, M, S, seeds, push)
            print(f"| {push:g} | {k:g} | {s0:g} | {np.mean(~res.fell):.0%} | "
                  f"{np.mean(m['speed_error_mps']):.3f} |", flush=True)


if __name__ == "__main__":
    main()
