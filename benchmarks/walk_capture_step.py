"""Does stepping to the capture point catch the pushes the walk does not? The walk engine of
``humanoid-walk`` with its swing foot placed by the capture point, told the torso's true
velocity (an oracle: no NAO sensor gives it).

    python benchmarks/walk_capture_step.py [--worlds 100] [--duration 6] [--pushes 2 3 4 5]
        [--periods 0.48 0.36] [--gain 1.0]

The engine (``omni_gait``, online leg IK, no other feedback) steps in place (zero command) in
the nominal world, one push per world (``humanoid-walk compare``'s unseen world seeds,
shifted by ``--seed``: the push's size fixed, its direction and time drawn). Two rows per gait
period ``T`` (the engine steps every ``T / 2`` s):

- ``engine``: the plain engine (``benchmarks/walk_push_oracle.py``'s engine row);
- ``capture step``: every control step (20 ms), the swing foot's landing point moves to
  ``gain x Δv / ω`` from where the engine puts it (``omni_gait.targets``' ``foot_offsets``),
  ``Δv`` the torso's x/y velocity (in its own, leaning frame) less the nominal stepping's at
  the same phase (a table from 8 unpushed cycles), ``ω = √(g / 0.243 m)`` (the model's CoM
  height): the capture point's offset caused by the push (Pratt et al. 2006). The swing foot
  blends from its lift-off offset to it along the swing's cosine; the stance foot keeps its
  offset until it lifts. Offsets are clipped to ±0.1 m forward and to 0.08 m outward, 0.01 m
  inward (no crossing); 0.07 or 0.13 m forward changed nothing (50 worlds, 2026-12-06).

``benchmarks/push_capturability.py`` gives the linear inverted pendulum's estimate of what any
stepping at that pace could catch. Output: a markdown table of survival (no fall by the end).
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from markdown_table import markdown_table

COM_HEIGHT_M = 0.243  # the NAO model's CoM in the walk's nominal pose (push_capturability.py)
REACH_X_M, OUT_Y_M, IN_Y_M = 0.10, 0.08, 0.01


class CaptureStep:
    """The engine's policy with capture-point foot placement (module doc); ``gain`` 0 is the
    plain engine. State per world: each foot's offset, its offset at lift-off, swinging."""

    def __init__(self, problem, sim, n: int, gain: float, v_nominal: np.ndarray | None,
                 record: bool = False) -> None:
        self.ctl, self.gain, self.v_nominal = problem.ctl, float(gain), v_nominal
        names = list(sim.observe.names)
        self.iv = [names.index(f"torso_velocity:{a}") for a in "xy"]
        self.iph = names.index("phase:sin"), names.index("phase:cos")
        self.ic = [names.index(f"command:{i}") for i in range(3)]
        self.omega = math.sqrt(9.81 / COM_HEIGHT_M)
        self.offset, self.lift_off = np.zeros((n, 2, 2)), np.zeros((n, 2, 2))
        self.swinging = np.zeros((n, 2), bool)
        #: (phase, velocity) per control step, kept only when ``record`` (nominal_velocity)
        self.seen: list[tuple[np.ndarray, np.ndarray]] | None = [] if record else None

    def __call__(self, rows: np.ndarray, obs: np.ndarray) -> np.ndarray:
        from evomotion.studies.humanoid_omniwalk.omni_gait import targets

        ctl, gait = self.ctl, self.ctl.gait
        phase = np.arctan2(obs[:, self.iph[0]], obs[:, self.iph[1]]) / (2 * np.pi) % 1.0
        v = obs[:, self.iv]
        if self.seen is not None:
            self.seen.append((phase, v))
        dv = np.zeros_like(v)
        if self.v_nominal is not None:
            nb = len(self.v_nominal)
            dv = v - self.v_nominal[np.round(phase * nb).astype(int) % nb]
        land = self.gain * dv / self.omega
        off, lift_off = self.offset[rows], self.lift_off[rows]
        w, ahead = gait.swing_fraction, ctl.control_dt / gait.period_s
        for f, side in ((0, 1.0), (1, -1.0)):
            p = (phase + 0.5 * f) % 1.0
            swing = p < w
            new = swing & ~self.swinging[rows, f]
            lift_off[new, f] = off[new, f]
            goal = np.stack([np.clip(land[:, 0], -REACH_X_M, REACH_X_M),
                             side * np.clip(side * land[:, 1], -IN_Y_M, OUT_Y_M)], axis=1)
            a = 0.5 * (1.0 - np.cos(np.pi * np.clip((p + ahead) / w, 0.0, 1.0)))
            moving = lift_off[:, f] + (goal - lift_off[:, f]) * a[:, None]
            off[:, f] = np.where(swing[:, None], moving, off[:, f])
            self.swinging[rows, f] = swing
        self.offset[rows], self.lift_off[rows] = off, lift_off
        full = targets(gait, phase, obs[:, self.ic], off)
        return full[:, ctl.columns] - ctl.nominal[ctl.columns]


def build(period_s: float, duration_s: float):
    """(problem, simulator reading the torso's velocity) for the engine at ``period_s``."""
    from evomotion.sim.closed_loop import ClosedLoopSimulator
    from evomotion.sim.observations import ObservationSpec
    from evomotion.studies.humanoid_omniwalk.problem import OmniWalkConfig, OmniWalkProblem

    p = OmniWalkProblem(OmniWalkConfig(duration_s=duration_s, perturb=False, period_s=period_s))
    ctl, r = p.ctl, p.ctl.robot
    spec = ObservationSpec(("torso_velocity", "phase", "command"),
                           phase_period_s=ctl.gait.period_s, command_size=3)
    sim = ClosedLoopSimulator(r, spec, ctl.sim.k, p.sim.nthread, columns=ctl.columns,
                              nominal=ctl.nominal,
                              followers=[(r.joints.index(a), r.joints.index(b))
                                         for a, b in ctl.followers.items()])
    p.sim.close()
    return p, sim


def nominal_velocity(p, sim, cycles: int = 8) -> np.ndarray:
    """The unpushed engine's torso velocity ``[bins, 2]`` by phase (one bin per control step
    of a cycle; the first two cycles left out)."""
    nb = int(round(p.ctl.gait.period_s / p.ctl.control_dt))
    eng = CaptureStep(p, sim, 1, 0.0, None, record=True)
    sim.run(eng, 1, int(cycles * p.ctl.gait.period_s / p.dt), commands=np.zeros((1, 3)),
            initial_state=p.ctl.state0)
    seen = eng.seen or []
    phase = np.array([s[0][0] for s in seen])[2 * nb:]
    v = np.array([s[1][0] for s in seen])[2 * nb:]
    b = np.round(phase * nb).astype(int) % nb
    return np.array([v[b == i].mean(axis=0) for i in range(nb)])


def measure(worlds: int, duration_s: float, pushes, periods, gain: float, seed: int):
    from evomotion.studies.humanoid_omniwalk.compare import EVAL_SEED_BASE, MAX_WORLDS

    seeds = EVAL_SEED_BASE + seed * MAX_WORLDS + np.arange(worlds)
    rows = []
    for period in periods:
        p, sim = build(period, duration_s)
        v_nominal = nominal_velocity(p, sim)
        for name, g in (("engine", 0.0), (f"capture step (gain {gain:g})", gain)):
            row = [f"{period:g}", name]
            for push in pushes:
                eng = CaptureStep(p, sim, worlds, g, v_nominal)
                res = sim.run(eng, p.worlds(seeds, push), p.nstep,
                              commands=np.zeros((worlds, 3)), initial_state=p.ctl.state0)
                row.append(f"{(res.fall_step >= p.nstep).mean():.0%}")
            rows.append(row)
        sim.close()
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--worlds", type=int, default=100)
    ap.add_argument("--duration", type=float, default=6.0)
    ap.add_argument("--pushes", type=float, nargs="+", default=[2.0, 3.0, 4.0, 5.0])
    ap.add_argument("--periods", type=float, nargs="+", default=[0.48, 0.36])
    ap.add_argument("--gain", type=float, default=1.0)
    ap.add_argument("--seed", type=int, default=7)
    a = ap.parse_args(argv)
    if (a.worlds < 1 or a.duration <= 0 or a.seed < 0 or min(a.pushes) < 0
            or min(a.periods) <= 0):
        ap.error("expected --worlds >= 1, --duration > 0, --seed >= 0, pushes >= 0, "
                 "periods > 0")
    from evomotion.errors import InputError

    try:
        rows = measure(a.worlds, a.duration, a.pushes, a.periods, a.gain, a.seed)
    except InputError as e:
        ap.error(str(e))
    head = ["period (s)", "engine"] + [f"{p:g} N s" for p in a.pushes]
    print(f"{a.worlds} nominal worlds x {a.duration:g} s, stepping in place, one push each")
    print(markdown_table(head, rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
