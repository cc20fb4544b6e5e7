"""Would a hip (and arm) strategy catch the pushes capture steps miss? A probe on a
humanoid-walk run with capture steps (issue 34): on top of the layer's action, both hips'
pitch and both shoulders' pitch move with the layer's own sagittal velocity offset ``Δv_x``
(eq. (2) of ``studies/humanoid_omniwalk/capture_step.py``, less its dead band, m/s):

    Δq_hip_pitch = k_back · min(Δv_x, 0) + k_front · max(Δv_x, 0)        (rad)
    Δq_shoulder_pitch = k_arm · Δv_x                                      (rad)

so a backward push (``Δv_x < 0``) bends the torso forward over the hips (hip flexion, the NAO's
hip pitch negative) and swings the arms forward, as in the hip strategy of human and humanoid
balance (Horak & Nashner 1986; Stephens, "Humanoid push recovery", Humanoids 2007: the
torso's angular momentum moves the centroidal moment pivot beyond the sole). Patched in this
process only; the first variant ``0 0 0`` is the run as it is.

Every world (``humanoid-walk compare``'s unseen seeds, perturbed) gets one push of each
``--push`` size under the run's random command schedule; survival over ``--duration`` s, in
all and by the push's direction in the robot's frame at the push (within 45° of forward,
backward, left, right: as ``walk_falls.py``).

    python benchmarks/capture_step_hip_probe.py RUN [--variants "0 0 0" "2 0 0" ...]
        [--push 3 4] [--worlds 100] [--duration 6]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from evomotion.studies.humanoid_omniwalk import capture_step  # noqa: E402
from markdown_table import markdown_row, markdown_table  # noqa: E402
from walk_falls import SIDES, push_sides, side_cells  # noqa: E402

ORIGINAL = capture_step.CaptureStep.__call__
GAINS = [0.0, 0.0, 0.0]  # k_back, k_front, k_arm (rad per m/s)


def patched(self, rows, obs, action):
    """The layer, then the hips and shoulders moved by its own velocity offset."""
    out = ORIGINAL(self, rows, obs, action)
    kb, kf, ka = GAINS
    if not (kb or kf or ka):
        return out
    phase = self.phase(obs)
    b = np.round(phase * self.bins).astype(np.int64) % self.bins
    # the sway after this step's update: it is only updated where |Δv| is below the dead band
    dv = self.velocity_of(rows, obs, phase) - obs[:, self.ic[:2]] - self.sway[rows, b]
    dv = np.where(np.isfinite(dv).all(axis=1, keepdims=True), dv, 0.0)
    dv = np.where((self.steps[rows] > capture_step.WARMUP_CYCLES * self.bins)[:, None], dv, 0.0)
    size = np.linalg.norm(dv, axis=1, keepdims=True)
    dv = dv * np.maximum(size - self.deadband, 0.0) / np.maximum(size, 1e-12)
    x = dv[:, 0]
    hip = kb * np.minimum(x, 0.0) + kf * np.maximum(x, 0.0)
    names = list(self.ctl.driven)
    out = out.copy()
    for j in ("LHipPitch", "RHipPitch"):
        out[:, names.index(j)] += hip
    for j in ("LShoulderPitch", "RShoulderPitch"):
        out[:, names.index(j)] += ka * x
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run")
    ap.add_argument("--variants", nargs="+", default=["0 0 0", "1 0 0", "2 0 0", "2 0 2"])
    ap.add_argument("--push", type=float, nargs="+", default=[3.0, 4.0])
    ap.add_argument("--worlds", type=int, default=100)
    ap.add_argument("--duration", type=float, default=6.0)
    ap.add_argument("--seed", type=int, default=7)
    a = ap.parse_args()
    from evomotion.studies.humanoid_omniwalk.commands import heading_at
    from evomotion.studies.humanoid_omniwalk.compare import EVAL_SEED_BASE, MAX_WORLDS, load_run

    capture_step.CaptureStep.__call__ = patched  # type: ignore[method-assign]
    problem, pol, _ = load_run(a.run, a.duration)
    if not problem.cfg.capture_gain:
        ap.error(f"{a.run}: no capture steps (problem.capture_gain 0)")
    seeds = EVAL_SEED_BASE + a.seed * MAX_WORLDS + np.arange(a.worlds)
    n, dt = len(seeds), problem.ctl.control_dt
    P, M, S = (np.tile(v, (n, 1)) for v in (pol.params, pol.obs_mean, pol.obs_std))
    head = ["k_back, k_front, k_arm", "push (N s)", "survival"] + [f"pushed {s}" for s in SIDES]
    rows = []
    for v in a.variants:
        GAINS[:] = [float(x) for x in v.split()]
        for push in a.push:
            ws = problem.worlds(seeds, push)
            _, res, _ = problem.play(P, M, S, seeds, push)
            up = res.fall_step >= problem.nstep
            side = push_sides(ws, heading_at(res.torso, np.array([w.push_time_s for w in ws]),
                                             dt))
            rows.append([v, f"{push:g}", f"{up.mean():.0%}", *side_cells(up, side)])
            print(markdown_row(rows[-1]), flush=True)
    print(f"\n{a.run}: {n} worlds x {a.duration:g} s, one push each, random commands\n")
    print(markdown_table(head, rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
