"""Does telling a humanoid-walk controller its command differently mend its tracking error
after a change of command? (issue 34's 15 %: two thirds of the every-window error is in the
second after a change, ``walk_tracking_breakdown.py``.) No retraining; the errors are always
against the ramped commands the schedule gives.

- **lag**: the shift ``s`` (0-0.6 s) for which the walked velocities best match the ramped
  command ``s`` earlier (``Σ|v(t) − v_cmd(t − s)|`` least over every window while up); a walk
  that followed its command with a pure delay ``τ`` has its least at ``s = τ``.
- **steady gains**: each command component alone at several values, 6 unseen worlds without a
  push, the walked value over the last half of 8 s (the curves a calibration inverts).
- rows: the robot told each command's ramp ``τ`` ahead (**preview**: a ramp is known once its
  command is given, the next command is not: the ramp starts with a jump of ``τ / ramp_s`` of
  the change and ends ``τ`` sooner), or told the **calibrated** command (each component through
  the inverse of its steady gain curve, piecewise linear), on compare's unseen worlds with the
  run's pushes: survival, the every-window error, its "after a change" part and the
  every-window error against the commands as given (each reached at once, no ramp).

    python benchmarks/walk_command_shaping_probe.py RUN [--previews 0 0.1 0.2 0.3]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from markdown_table import markdown_row, markdown_table  # noqa: E402
from walk_tracking_breakdown import parts, played  # noqa: E402

#: the values each command component (vx m/s, vy m/s, ω rad/s) is held at for its gain curve
LEVELS = ((-0.2, -0.1, 0.1, 0.2, 0.3, 0.45), (-0.2, -0.1, 0.1, 0.2),
          (-1.2, -0.9, -0.6, -0.3, 0.3, 0.6, 0.9, 1.2))
GAIN_WORLDS, GAIN_S = 6, 8.0


def lag_errors(problem, pol, seeds, shifts: np.ndarray) -> np.ndarray:
    """``Σ|v − v_cmd(t − s)|`` per window while up, per shift ``s`` (control steps)."""
    from evomotion.studies.humanoid_omniwalk.commands import schedules, tracking

    C = -(-problem.nstep // problem.control_steps)
    cmds = schedules(problem.command_draw, seeds, np.arange(C) * problem.ctl.control_dt)
    res = played(problem, pol, seeds, None, cmds)
    W = problem.ctl.window
    up = np.arange(W, C + 1)[None] * problem.control_steps <= res.fall_step[:, None]
    out = []
    for s in shifts:
        late = np.concatenate([np.zeros_like(cmds[:, :s]), cmds[:, :C - s]], axis=1)
        ev, _ = tracking(res.torso, late, W, problem.ctl.control_dt).errors()
        ok = up & (np.arange(ev.shape[1])[None] >= s)  # windows whose shifted command exists
        out.append(float((ev * ok).sum() / ok.sum()))
    return np.array(out)


def gain_curves(run: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per component, (commanded, walked) with the origin, from :data:`LEVELS` (module doc)."""
    from evomotion.studies.humanoid_omniwalk.commands import tracking
    from evomotion.studies.humanoid_omniwalk.compare import EVAL_SEED_BASE, load_run

    problem, pol, _ = load_run(run, GAIN_S)
    C = -(-problem.nstep // problem.control_steps)
    t = np.arange(C) * problem.ctl.control_dt
    ramp = np.clip(t / problem.cfg.ramp_s, 0.0, 1.0)
    curves = []
    for k, levels in enumerate(LEVELS):
        cmds = np.zeros((len(levels) * GAIN_WORLDS, C, 3))
        cmds[..., k] = np.repeat(levels, GAIN_WORLDS)[:, None] * ramp
        seeds = np.tile(EVAL_SEED_BASE + 5000 + np.arange(GAIN_WORLDS), len(levels))
        res = played(problem, pol, seeds, 0.0, cmds)
        tr = tracking(res.torso, cmds, problem.ctl.window, problem.ctl.control_dt)
        q = (tr.vx, tr.vy, tr.yaw_rate)[k]
        walked = q[:, q.shape[1] // 2:].mean(axis=1)
        w = [float(walked[b][~res.fell[b]].mean()) for b in
             np.split(np.arange(len(seeds)), len(levels))]
        curves.append((np.array([0.0, *levels]), np.array([0.0, *w])))
    problem.sim.close()
    return curves


def calibrated(curves):
    """``tell`` for :func:`parts`: each component through its curve's inverse, clipped to the
    commanded range."""
    def tell(cmds: np.ndarray) -> np.ndarray:
        out = cmds.copy()
        for k, (x, y) in enumerate(curves):
            o = np.argsort(y)
            out[..., k] = np.clip(np.interp(cmds[..., k], y[o], x[o]), x.min(), x.max())
        return out
    return tell


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run")
    ap.add_argument("--previews", type=float, nargs="+", default=[0.0, 0.1, 0.2, 0.3])
    ap.add_argument("--worlds", type=int, default=100)
    ap.add_argument("--duration", type=float, default=60.0)
    a = ap.parse_args()
    from evomotion.studies.humanoid_omniwalk.compare import EVAL_SEED_BASE, load_run

    curves = gain_curves(a.run)
    for name, (x, y) in zip(("vx", "vy", "ω"), curves):
        print(f"steady {name}: " + ", ".join(f"{c:+.2f} -> {w:+.3f}" for c, w in
                                              zip(x[1:], y[1:])))
    problem, pol, _ = load_run(a.run, a.duration)
    seeds = EVAL_SEED_BASE + np.arange(a.worlds)
    dt = problem.ctl.control_dt
    shifts = np.arange(0, int(round(0.6 / dt)) + 1, max(1, int(round(0.04 / dt))))
    err = np.mean([lag_errors(problem, pol, seeds[b:b + 20], shifts)
                   for b in range(0, len(seeds), 20)], axis=0)
    print("lag: mean |v - v_cmd(t - s)| (m/s): " + ", ".join(
        f"{s * dt:.2f} s {e:.4f}" for s, e in zip(shifts, err)))
    print(f"least at s = {shifts[int(np.argmin(err))] * dt:.2f} s\n", flush=True)
    head = ["told", "survival", "speed: every window", "after a change", "against the steps",
            "yaw rate: every window", "after a change", "against the steps"]
    rows = []
    for name, kw in [(f"preview {tau:g} s", {"preview_s": tau}) for tau in a.previews] + [
            ("calibrated", {"tell": calibrated(curves)})]:
        p = parts(problem, pol, seeds, None, **kw)
        rows.append([name, f"{p['survived']:.0%}"] + [
            f"{p[q + k]:.1%}" for q in ("v:", "w:") for k in ("all", "after a change",
                                                              "steps")])
        print(markdown_row(rows[-1]), flush=True)
    problem.sim.close()
    print(f"\n{a.run}: {a.worlds} worlds x {a.duration:g} s, the run's pushes\n")
    print(markdown_table(head, rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
