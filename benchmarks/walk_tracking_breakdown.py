"""Where does a humanoid-walk controller's tracking error over every window come from? The
relative speed error of ``humanoid-walk compare`` (``Σ|v − v_cmd| / Σ|v_cmd|`` over the
one-cycle windows while up) split by window into three parts that add up to it:

- **held**: windows beginning ``SETTLE_S`` (1 s) or more after the command last changed (its
  ramp included) with ``|v_cmd| ≥ 0.05`` m/s (the numerator of compare's "steady" error);
- **drift**: such settled windows with a smaller commanded velocity (turning in place,
  standing): any walked velocity there is error, and nothing is added to the denominator;
- **after a change**: the windows within ``SETTLE_S`` of a change (the response to it).

A second table splits the settled (held + drift) and after-a-change parts by the kind of the
command given at the window's end (forward/backward, sideways, turning, mixed, standing).

Each part is its numerator over the same denominator (all windows' ``Σ|v_cmd|``); the yaw rate
likewise (``|ω_cmd| ≥ 0.1`` rad/s held). Played with the run's pushes and again with every
push 0 N s, on compare's 100 unseen perturbed worlds x 60 s of random commands.

    python benchmarks/walk_tracking_breakdown.py RUN [RUN ...] [--worlds 100] [--duration 60]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from markdown_table import markdown_row, markdown_table  # noqa: E402

#: the kinds of command (commands.py) as :func:`command_kind` names them
KINDS = ("forward/backward", "sideways", "turning", "mixed", "standing")


def command_kind(cmds: np.ndarray) -> np.ndarray:
    """The kind (:data:`KINDS`) of each command ``cmds[..., 3]`` as given (unramped)."""
    nz = np.abs(cmds) > 1e-12
    return np.select([nz[..., 0] & ~nz[..., 1:].any(-1), nz[..., 1] & ~nz[..., ::2].any(-1),
                      nz[..., 2] & ~nz[..., :2].any(-1), nz.all(-1)], list(KINDS[:4]), KINDS[4])


def played(problem, pol, seeds, push_ns: float | None, commands: np.ndarray):
    """The closed-loop result of the exported policy ``pol`` in the worlds of ``seeds`` told
    ``commands[n, C, 3]``."""
    n = len(seeds)
    return problem.play(*(np.tile(x, (n, 1)) for x in (pol.params, pol.obs_mean, pol.obs_std)),
                        seeds, push_ns, commands=commands)[1]


def parts(problem, pol, seeds, push_ns: float | None, batch: int = 20,
          preview_s: float = 0.0, tell=None) -> dict[str, float]:
    """The every-window relative errors' parts (module doc), speed ``v:`` and yaw rate ``w:``,
    ``v:steps`` and ``w:steps`` (every window's against the commands as given, unramped), the
    settled and after-a-change parts by the kind of the command given at the window's end
    (``v:settled to turning``, ...), and
    ``survived`` (the share of episodes up at the end). With ``preview_s`` the robot is
    told each ramp that much ahead (:func:`~evomotion.studies.humanoid_omniwalk.commands.
    command_schedule`), and with ``tell`` it is told ``tell(commands[n, C, 3])`` of them (e.g. a
    calibration), the errors still against the ramped commands."""
    from dataclasses import replace

    from evomotion.studies.humanoid_omniwalk import compare as c
    from evomotion.studies.humanoid_omniwalk.commands import schedules, tracking

    at_once = replace(problem.command_draw, ramp_s=1e-9)

    sums: dict[str, float] = {"survived": 0.0}
    t = np.arange(-(-problem.nstep // problem.control_steps)) * problem.ctl.control_dt
    for a in range(0, len(seeds), batch):
        s = seeds[a:a + batch]
        cmds = schedules(problem.command_draw, s, t)
        told = schedules(problem.command_draw, s, t, preview_s) if preview_s else cmds
        res = played(problem, pol, s, push_ns, told if tell is None else tell(told))
        sums["survived"] += float((~res.fell).sum()) / len(seeds)
        tr = tracking(res.torso, cmds, problem.ctl.window, problem.ctl.control_dt)
        ev, ew = tr.errors()
        ends = np.arange(problem.ctl.window, cmds.shape[1] + 1)
        up = ends[None] * problem.control_steps <= res.fall_step[:, None]
        settled = up & c.steady_windows(cmds, problem.ctl.window,
                                        int(round(c.SETTLE_S / problem.ctl.control_dt)))
        cv, cw = np.hypot(tr.cmd[..., 0], tr.cmd[..., 1]), np.abs(tr.cmd[..., 2])
        given = schedules(at_once, s, t)
        steps = tracking(res.torso, given, problem.ctl.window, problem.ctl.control_dt).errors()
        kinds = command_kind(given[:, ends - 1])  # the command given at each window's end
        for q, e, cmd, lo in (("v", ev, cv, c.STEADY_MIN_V_MPS), ("w", ew, cw,
                                                                   c.STEADY_MIN_W_RPS)):
            held = settled & (cmd >= lo)
            for key, mask in (("held", held), ("drift", settled & ~held),
                              ("after a change", up & ~settled), ("all", up)):
                sums[f"{q}:{key}"] = sums.get(f"{q}:{key}", 0.0) + float((e * mask).sum())
            sums[f"{q}:steps"] = sums.get(f"{q}:steps", 0.0) + float(
                (steps["vw".index(q)] * up).sum())
            for kind in KINDS:
                for key, mask in (("settled", settled), ("after a change", up & ~settled)):
                    k = f"{q}:{key} to {kind}"
                    sums[k] = sums.get(k, 0.0) + float((e * mask * (kinds == kind)).sum())
            sums[f"{q}:cmd"] = sums.get(f"{q}:cmd", 0.0) + float((cmd * up).sum())
    return {k: v if k == "survived" else v / sums[k[:2] + "cmd"]
            for k, v in sums.items() if not k.endswith("cmd")}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--worlds", type=int, default=100)
    ap.add_argument("--duration", type=float, default=60.0)
    a = ap.parse_args()
    from evomotion.studies.humanoid_omniwalk.compare import EVAL_SEED_BASE, load_run

    head = ["run", "pushes", "speed: every window = held + drift + after a change",
            "yaw rate: every window = held + drift + after a change"]
    rows, by_kind = [], []
    for run in a.runs:
        problem, pol, _ = load_run(run, a.duration)
        seeds = EVAL_SEED_BASE + np.arange(a.worlds)
        for name, push in (("the run's", None), ("none", 0.0)):
            p = parts(problem, pol, seeds, push)
            rows.append([run, name] + [
                f"{p[q + ':all']:.1%} = {p[q + ':held']:.1%} + {p[q + ':drift']:.1%} + "
                f"{p[q + ':after a change']:.1%}" for q in "vw"])
            print(markdown_row(rows[-1]), flush=True)
            if push is None:
                by_kind += [[run, what] + [
                    f"{p[f'{q}:settled to {k}']:.1%} + {p[f'{q}:after a change to {k}']:.1%}"
                    for k in KINDS] for q, what in (("v", "speed"), ("w", "yaw rate"))]
        problem.sim.close()
    print(f"\n{a.worlds} worlds x {a.duration:g} s, random commands\n")
    print(markdown_table(head, rows))
    print("\nthe run's pushes, by the kind of command given (settled + after a change; "
          "they add up to every window)\n")
    print(markdown_table(["run", "error"] + list(KINDS), by_kind))
    return 0


if __name__ == "__main__":
    sys.exit(main())
