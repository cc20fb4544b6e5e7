"""Does stepping to the capture point catch the pushes the walk does not? The walk engine of
``humanoid-walk``, or a run's evolved controller, with its swing foot placed by the capture
point (``studies/humanoid_omniwalk/capture_step.py``, ``problem.capture_gain``), told the
torso's true velocity (an oracle: no NAO sensor gives it) or estimating it by leg odometry.

    python benchmarks/walk_capture_step.py [--worlds 100] [--duration 6] [--pushes 2 3 4 5]
        [--periods 0.48 0.36] [--gain 1.0]
    python benchmarks/walk_capture_step.py --run RUN [--gain 0.7] [--worlds 100] ...

The engine (``omni_gait``, online leg IK, no other feedback) steps in place (zero command) in
the nominal world, one push per world (``humanoid-walk compare``'s unseen world seeds,
shifted by ``--seed``: the push's size fixed, its direction and time drawn). Two rows per gait
period ``T`` (the engine steps every ``T / 2`` s):

- ``engine``: the plain engine (``benchmarks/walk_push_oracle.py``'s engine row);
- ``capture step``: every control step (20 ms), the swing foot's landing point moves to
  ``gain x Δv / ω`` from where the engine puts it (``omni_gait.targets``' ``foot_offsets``),
  ``Δv`` the torso's true x/y velocity (in its own, leaning frame) less the command's and less
  the nominal stepping's at the same phase (a table from 8 unpushed cycles, the first two left
  out), ``ω = √(g / z_com)``: the capture point's offset caused by the push (Pratt et al.
  2006). The swing foot blends from its lift-off offset to it along the swing's cosine; the
  stance foot keeps its offset until it lifts. Offsets are clipped to ±0.1 m forward and to
  0.08 m outward, 0.01 m inward (no crossing); 0.07 or 0.13 m forward changed nothing (50
  worlds, 2026-12-06). No dead band here (the layer's ``DEADBAND_MPS`` set to 0).

With ``--run`` (a ``humanoid-walk`` run folder; ``--periods`` unused, the run's own): the
run's controller instead of the engine, three rows per world: the plain controller; with the
oracle's capture step (the table from the controller stepping in place, the layer's dead
band); with the capture step the controller runs under ``problem.capture_gain`` (the velocity
by leg odometry, the sway learnt online). Two worlds: the nominal one stepping in place (as
the engine), and the perturbed worlds under the run's random command schedules (as it
trained and ``compare`` measures).

``benchmarks/push_capturability.py`` gives the linear inverted pendulum's estimate of what any
stepping at that pace could catch. Output: a markdown table of survival (no fall by the end).
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from markdown_table import markdown_table


class Play:
    """A closed-loop policy: ``base(obs)`` (the engine's action when None) plus the capture
    step ``layer`` (None: none); ``record`` keeps (phase, true velocity) per control step."""

    def __init__(self, ctl, names: list[str], base=None, layer=None, record: bool = False):
        self.ctl, self.base, self.layer = ctl, base, layer
        self.iv = [names.index(f"torso_velocity:{a}") for a in "xy"]
        self.iph = names.index("phase:sin"), names.index("phase:cos")
        self.ic = [names.index(f"command:{i}") for i in range(3)]
        self.seen: list[tuple[np.ndarray, np.ndarray]] | None = [] if record else None

    def __call__(self, rows: np.ndarray, obs: np.ndarray) -> np.ndarray:
        ctl = self.ctl
        phase = np.arctan2(obs[:, self.iph[0]], obs[:, self.iph[1]]) / (2 * np.pi) % 1.0
        if self.seen is not None:
            self.seen.append((phase, obs[:, self.iv]))
        if self.base is None:
            act = ctl.engine(phase, obs[:, self.ic])[:, ctl.columns] - ctl.nominal[ctl.columns]
        else:
            act = self.base(obs)
        return act if self.layer is None else self.layer(rows, obs, act)


def reading(ctl, channels: tuple[str, ...]):
    """``ctl``'s simulator reading ``channels`` (its threads)."""
    from evomotion.sim.observations import ObservationSpec

    spec = ObservationSpec(channels, phase_period_s=ctl.gait.period_s, command_size=3)
    return ctl.simulator(spec, ctl.sim.nthread)


def nominal_velocity(p, sim, base=None, cycles: int = 8) -> np.ndarray:
    """The unpushed engine's (``base``'s) torso velocity ``[bins, 2]`` by phase, stepping in
    place in the nominal world (one bin per control step of a cycle; the first two cycles
    left out)."""
    nb = int(round(p.ctl.gait.period_s / p.ctl.control_dt))
    play = Play(p.ctl, list(sim.observe.names), base, record=True)
    sim.run(play, 1, int(cycles * p.ctl.gait.period_s / p.dt), commands=np.zeros((1, 3)),
            initial_state=p.ctl.state0)
    seen = play.seen or []
    phase = np.array([s[0][0] for s in seen])[2 * nb:]
    v = np.array([s[1][0] for s in seen])[2 * nb:]
    b = np.round(phase * nb).astype(int) % nb
    return np.array([v[b == i].mean(axis=0) for i in range(nb)])


def survival(p, sim, seeds, push, commands, base, layer) -> str:
    names = list(sim.observe.names)
    res = sim.run(Play(p.ctl, names, base, layer), p.worlds(seeds, push), p.nstep,
                  commands=commands, initial_state=p.ctl.state0)
    return f"{(res.fall_step >= p.nstep).mean():.0%}"


def oracle(p, sim, n: int, gain: float, v_nominal: np.ndarray, deadband_mps: float):
    """The capture step told the true velocity, with the fixed table ``v_nominal``."""
    from evomotion.studies.humanoid_omniwalk.capture_step import CaptureStep

    names = list(sim.observe.names)
    velocity = [names.index(f"torso_velocity:{a}") for a in "xy"]
    return CaptureStep(p.ctl, names, n, gain, velocity=velocity, sway=v_nominal,
                       deadband_mps=deadband_mps)


def measure(worlds: int, duration_s: float, pushes, periods, gain: float, seed: int):
    from evomotion.studies.humanoid_omniwalk.compare import EVAL_SEED_BASE, MAX_WORLDS
    from evomotion.studies.humanoid_omniwalk.controller import CHANNELS
    from evomotion.studies.humanoid_omniwalk.problem import OmniWalkConfig, OmniWalkProblem

    seeds = EVAL_SEED_BASE + seed * MAX_WORLDS + np.arange(worlds)
    rows = []
    for period in periods:
        p = OmniWalkProblem(OmniWalkConfig(duration_s=duration_s, perturb=False,
                                           period_s=period))
        sim = reading(p.ctl, (*CHANNELS, "torso_velocity"))
        p.sim.close()
        v_nominal, zero = nominal_velocity(p, sim), np.zeros((worlds, 3))
        rows.append([f"{period:g}", "engine"] + [
            survival(p, sim, seeds, push, zero, None, None) for push in pushes])
        rows.append([f"{period:g}", f"capture step (gain {gain:g})"] + [
            survival(p, sim, seeds, push, zero, None,
                     oracle(p, sim, worlds, gain, v_nominal, 0.0))
            for push in pushes])
        sim.close()
    return rows


def measure_run(run: str, worlds: int, duration_s: float, pushes, gain: float, seed: int):
    """The rows of a run's controller (module doc)."""
    import dataclasses

    from evomotion.studies.humanoid_omniwalk.capture_step import DEADBAND_MPS, CaptureStep
    from evomotion.studies.humanoid_omniwalk.commands import schedules
    from evomotion.studies.humanoid_omniwalk.compare import (
        EVAL_SEED_BASE,
        MAX_WORLDS,
        load_run,
    )
    from evomotion.studies.humanoid_omniwalk.controller import CHANNELS
    from evomotion.studies.humanoid_omniwalk.problem import OmniWalkProblem

    seeds = EVAL_SEED_BASE + seed * MAX_WORLDS + np.arange(worlds)
    loaded, pol, _ = load_run(run, duration_s)
    loaded.sim.close()
    od, rows = loaded.obs_dim, []

    def base(obs: np.ndarray) -> np.ndarray:
        n = len(obs)
        return pol.spec.act(np.broadcast_to(pol.params, (n, pol.params.size)), obs[:, :od],
                            np.broadcast_to(pol.obs_mean, (n, od)),
                            np.broadcast_to(pol.obs_std, (n, od)))

    for perturb in (False, True):
        p = OmniWalkProblem(dataclasses.replace(loaded.cfg, perturb=perturb))
        sim = reading(p.ctl, (*CHANNELS, "torso_velocity"))
        names = list(sim.observe.names)
        assert names[:od] == list(p.obs_names)
        p.sim.close()
        v_nominal = nominal_velocity(p, sim, base)
        C = math.ceil(p.nstep / p.control_steps)
        commands = (schedules(p.command_draw, seeds, np.arange(C) * p.ctl.control_dt)
                    if perturb else np.zeros((worlds, C, 3)))
        world = "perturbed, random commands" if perturb else "nominal, in place"
        layers = {"controller": lambda: None,
                  f"+ capture step, true velocity (gain {gain:g})":
                      lambda: oracle(p, sim, worlds, gain, v_nominal, DEADBAND_MPS),
                  f"+ capture step, leg odometry (gain {gain:g})":
                      lambda: CaptureStep(p.ctl, names, worlds, gain)}
        for name, layer in layers.items():
            rows.append([world, name] + [survival(p, sim, seeds, push, commands, base, layer())
                                         for push in pushes])
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
    ap.add_argument("--run", help="a humanoid-walk run: its controller instead of the engine")
    a = ap.parse_args(argv)
    if (a.worlds < 1 or a.duration <= 0 or a.seed < 0 or min(a.pushes) < 0
            or min(a.periods) <= 0 or not 0 <= a.gain <= 3):
        ap.error("expected --worlds >= 1, --duration > 0, --seed >= 0, pushes >= 0, "
                 "periods > 0, 0 <= --gain <= 3")
    from evomotion.errors import InputError

    try:
        if a.run:
            rows = measure_run(a.run, a.worlds, a.duration, a.pushes, a.gain, a.seed)
        else:
            rows = measure(a.worlds, a.duration, a.pushes, a.periods, a.gain, a.seed)
    except InputError as e:
        ap.error(str(e))
    head = (["world", "controller"] if a.run else ["period (s)", "engine"]) + [
        f"{p:g} N s" for p in a.pushes]
    print(f"{a.run or 'engine'}: {a.worlds} worlds x {a.duration:g} s, one push each")
    print(markdown_table(head, rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
