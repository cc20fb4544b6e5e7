"""Would the walk survive a push if its command knew the push? An oracle probe of what limits
``humanoid-walk``'s push survival: the sensing (the controller not inferring the push) or the
gait's steps (what any command can make them do).

    python benchmarks/walk_push_oracle.py RUN [--worlds 100] [--duration 6] [--pushes 2 3 4]
    python benchmarks/walk_push_oracle.py --engine period_s=0.36 [--engine step_height_m=0.015]

Every world gets one push of the given size, at ``humanoid-walk compare``'s unseen world seeds
(shifted, ``--seed``), under a random command schedule (the run's own draw) or, for the engine,
no command. Then the same episodes with an **oracle**: from the control step that holds the
push on (up to one control period before it), for ``hold`` s, the command is replaced by a walk
at ``speed`` m/s along the push's direction in the robot's frame at the push (no turn; no ramp,
at once; ``vx``, ``vy`` clipped to ``--clip`` m/s: the default 0.45 clips nothing, so the
0.3 and 0.45 m/s oracles may command more than the walk's trained ranges, backward 0.2 m/s and
sideways 0.2 m/s), i.e. a command that knows what the IMU only hints at. Two controllers:

- ``controller``: the run's evolved controller, in perturbed worlds (as it trained) and in the
  nominal world (the same seeds draw other pushes there: directions and times are drawn after
  the perturbations, so the two rows are not paired);
- ``engine``: the walk engine it was fitted to (``omni_gait``, online leg IK, no feedback),
  standing-in-place command, nominal world: can the gait's steps, told where to go, catch a
  push at all? Without RUN only the engine is measured, at the study's engine settings; with
  ``--engine KEY=VALUE`` (``problem`` keys: ``period_s``, ``step_height_m``, ...) the engine
  rows use those over the run's (or the study's) settings; the controller rows never do.

Output: one markdown table of survival (episodes not fallen by the end).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys

import numpy as np

from markdown_table import markdown_table

#: the walk engine's settings ``--engine`` may change (problem keys, omni_gait.py)
ENGINE_KEYS = ("period_s", "swing_fraction", "step_height_m", "leg_height_m", "width_m",
               "sway_m", "lean_rad")
ORACLES = ((0.2, 1.0), (0.3, 1.0), (0.45, 1.0), (0.3, 0.5))  # (speed m/s, hold s)


class Probe:
    """One run's controller and engine, their worlds and plays (see the module doc)."""

    def __init__(self, run: str | None, duration_s: float, perturb: bool,
                 engine: dict | None = None) -> None:
        from evomotion.studies.humanoid_omniwalk.compare import load_run
        from evomotion.studies.humanoid_omniwalk.problem import OmniWalkConfig, OmniWalkProblem

        if run is None:  # the engine alone, at the study's settings
            cfg = OmniWalkConfig(duration_s=duration_s)
        else:
            problem, self.policy, _ = load_run(run, duration_s)
            problem.sim.close()
            cfg = problem.cfg
        self.problem = OmniWalkProblem(dataclasses.replace(cfg, perturb=perturb,
                                                           **(engine or {})))
        ctl = self.problem.ctl
        names = list(ctl.sim.observe.names)
        self._phase = names.index("phase:sin"), names.index("phase:cos")
        self._command = [names.index(f"command:{i}") for i in range(3)]

    def engine(self, rows: np.ndarray, obs: np.ndarray) -> np.ndarray:
        """The walk engine's targets at the observation's gait clock and command."""
        ctl = self.problem.ctl
        phase = np.arctan2(obs[:, self._phase[0]], obs[:, self._phase[1]]) / (2 * np.pi) % 1.0
        return ctl.engine(phase, obs[:, self._command])[:, ctl.columns] - \
            ctl.nominal[ctl.columns]

    def play(self, who: str, seeds: np.ndarray, push: float, worlds: list,
             commands: np.ndarray | None = None):
        """(survived[n], torso track, the commands played) of ``who`` ("controller" or
        "engine") in ``worlds`` (``seeds``' with ``push``); ``commands`` None: the run's
        schedules of ``seeds`` (the controller) or standing in place (the engine)."""
        from evomotion.sim.closed_loop import ClosedLoopResult

        p, n = self.problem, len(seeds)
        if who == "controller":  # the problem's own play: it builds the same worlds
            pol = self.policy
            _, res, commands = p.play(np.tile(pol.params, (n, 1)), np.tile(pol.obs_mean, (n, 1)),
                                      np.tile(pol.obs_std, (n, 1)), seeds, push,
                                      commands=commands)
        else:
            if commands is None:
                commands = np.zeros((n, math.ceil(p.nstep / p.control_steps), 3))
            res = p.ctl.sim.run(self.engine, worlds, p.nstep, commands=commands,
                                initial_state=p.ctl.state0)
        assert isinstance(res, ClosedLoopResult) and commands is not None
        return res.fall_step >= p.nstep, res.torso, commands

    def oracle(self, worlds, commands, torso, speed, hold, clip) -> np.ndarray:
        """``commands`` with the oracle's walk along the push from its control step."""
        from evomotion.studies.humanoid_omniwalk.commands import control_step_at, heading_at

        ws, dt = worlds, self.problem.ctl.control_dt
        push_t = np.array([w.push_time_s for w in ws])
        at = control_step_at(push_t, dt, torso.shape[1])
        push_dir = np.array([np.arctan2(w.push_ns[1], w.push_ns[0]) for w in ws])
        rel = push_dir - heading_at(torso, push_t, dt)
        walk = np.clip(speed * np.stack([np.cos(rel), np.sin(rel)], axis=1), -clip, clip)
        out = commands.copy()
        steps = np.arange(commands.shape[1])[None]
        on = (steps >= at[:, None]) & (steps < at[:, None] + int(round(hold / dt)))
        out[..., :2] = np.where(on[..., None], walk[:, None], out[..., :2])
        out[..., 2] = np.where(on, 0.0, out[..., 2])
        return out


def measure(run: str | None, worlds: int, duration_s: float, pushes: list[float], seed: int,
            clip: float, engine: dict | None = None) -> list[list[str]]:
    from evomotion.studies.humanoid_omniwalk.compare import EVAL_SEED_BASE, MAX_WORLDS

    seeds = EVAL_SEED_BASE + seed * MAX_WORLDS + np.arange(worlds)
    rows = []
    whom = [("controller", True), ("controller", False)] if run is not None else []
    for who, perturb in [*whom, ("engine", False)]:
        probe = Probe(run, duration_s, perturb, engine if who == "engine" else None)
        for push in pushes:
            ws = probe.problem.worlds(seeds, push)  # once per push: the oracles read them
            up, torso, cmds = probe.play(who, seeds, push, ws)
            row = [who, "perturbed" if perturb else "nominal", f"{push:g}", f"{up.mean():.0%}"]
            for speed, hold in ORACLES:
                cc = probe.oracle(ws, cmds, torso, speed, hold, clip)
                row.append(f"{probe.play(who, seeds, push, ws, cc)[0].mean():.0%}")
            rows.append(row)
        probe.problem.sim.close()
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", nargs="?", help="a humanoid-walk run (none: the engine alone)")
    ap.add_argument("--worlds", type=int, default=100)
    ap.add_argument("--duration", type=float, default=6.0)
    ap.add_argument("--pushes", type=float, nargs="+", default=[2.0, 3.0, 4.0])
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--clip", type=float, default=0.45, help="|vx|, |vy| of the oracle (m/s)")
    ap.add_argument("--engine", action="append", default=[], metavar="KEY=VALUE",
                    help="an engine setting (a problem key) for the engine's rows")
    a = ap.parse_args(argv)
    engine = {}
    for item in a.engine:
        key, eq, value = item.partition("=")
        try:
            engine[key.strip()] = float(value)
        except ValueError:
            ap.error(f"--engine {item!r}: expected KEY=NUMBER")
        if not eq or key.strip() not in ENGINE_KEYS:
            ap.error(f"--engine {item!r}: expected one of {', '.join(ENGINE_KEYS)}=NUMBER")
    if a.worlds < 1 or a.duration <= 0 or a.seed < 0 or a.clip <= 0 or min(a.pushes) < 0:
        ap.error("expected --worlds >= 1, --duration > 0, --seed >= 0, --clip > 0, pushes >= 0")
    from evomotion.errors import InputError
    from evomotion.studies.humanoid_omniwalk.problem import OmniWalkConfig

    try:
        OmniWalkConfig(**engine).validate()  # before minutes of the controller's rows
        rows = measure(a.run, a.worlds, a.duration, a.pushes, a.seed, a.clip, engine)
    except InputError as e:
        ap.error(str(e))
    head = ["who", "world", "push (N s)", "plain"] + [f"oracle {s:g} m/s, {h:g} s"
                                                      for s, h in ORACLES]
    print(f"{a.run or 'engine'} {engine or ''}: {a.worlds} worlds x {a.duration:g} s, "
          f"oracle |v| clipped to {a.clip:g}")
    print(markdown_table(head, rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
