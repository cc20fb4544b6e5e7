"""Probe (issue 33, balance at 4 N s): would a triggered reflex on top of the evolved policy
save the pushes from the front? A humanoid-balance run's exported policy (``RUN``), untrained
further, plus one of two hand-made reflexes, triggered once per episode when the capture point
estimated from the IMU lies more than ``thr`` m behind the stance centre
(``xi_x = h g_x + h gyro_y / w0``, ``h`` the stance's centre-of-mass height, ``w0 =
sqrt(9.81 / h)``: Pratt et al. 2006's capture point of the linear inverted pendulum, with the
torso's lean and pitch rate standing in for the centre of mass's offset and speed):

- ``step``: the front (left) foot steps back: its ankle moves by ``gain x xi`` (the capture
  point's offset, both axes, clipped to 0.2 m) over ``swing_s`` with a ``lift`` (m) sine
  arc, the target levelled by the IMU's gravity direction (the sole stays flat on the floor
  while the torso leans) and solved by the NAO's closed-form leg IK
  (:mod:`evomotion.sim.robots.nao.leg_ik`). With ``shift_s``, ``shift_m`` the body first
  shifts ``shift_m`` over the right foot in ``shift_s`` (both feet's targets move, levelled and
  solved alike): the stepping leg's targets replace the policy's; the stance leg's too, or with
  ``keep`` 1 the shift is added to the policy's action there, so the policy keeps balancing on
  the stance leg.
- ``hip``: both hip pitches flex by ``hip`` rad and both ankle pitches move by ``ankle`` rad,
  ramped in over ``ramp_s`` and released over 0.3 s after 0.6 s (a hip strategy: the torso
  thrown forward against the backward fall).

The probe first checks that the policy through its own wrapper, with the reflex never
triggered, gives the same falls and torso paths as ``compare``'s path (bit for bit). Survival
in ``--worlds`` unseen perturbed worlds (``compare``'s seeds) with every push ``--push`` N s;
"backward" are the pushes from the front (direction within 45 degrees of -x), which push the
robot backward.

    python benchmarks/balance_reflex_probe.py RUN --worlds 100 --push 4
"""

from __future__ import annotations

import argparse
import itertools
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from evomotion.sim.robots.nao.leg_ik import hip_position, leg_fk, leg_ik  # noqa: E402
from evomotion.studies.humanoid_balance.compare import eval_seeds, load_run  # noqa: E402
from evomotion.studies.humanoid_balance.episodes import push_range  # noqa: E402

LEG = ("HipYawPitch", "HipRoll", "HipPitch", "KneePitch", "AnklePitch", "AnkleRoll")
STEP = [dict(swing_s=0.15, thr=t, gain=1.0, lift=0.02) for t in (0.10, 0.13)] + [
    dict(shift_s=0.2, shift_m=0.04, keep=k, swing_s=s, thr=t, gain=1.0, lift=0.02)
    for k, s, t in itertools.product((0, 1), (0.15, 0.25), (0.10, 0.13))]
HIP = [dict(ramp_s=r, thr=0.10, hip=h, ankle=k) for r, h, k in
       itertools.product((0.04, 0.1), (-0.4, -0.8), (0.0, 0.15, -0.15))]


def level(g: np.ndarray) -> np.ndarray:
    """Rotations ``[n, 3, 3]`` taking the level frame's down (0, 0, -1) onto the measured
    gravity direction ``g[n, 3]`` (torso frame): level-frame vectors into the torso frame."""
    g = g / np.linalg.norm(g, axis=1, keepdims=True)
    a = np.array([0.0, 0.0, -1.0])
    v, c = np.cross(a, g), g @ a
    V = np.zeros((len(g), 3, 3))
    V[:, 0, 1], V[:, 0, 2], V[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    V[:, 1, 0], V[:, 2, 0], V[:, 2, 1] = v[:, 2], -v[:, 1], v[:, 0]
    return np.eye(3) + V + V @ V / (1.0 + c)[:, None, None]


class Reflex:
    """The exported policy plus one triggered reflex (module doc); ``kind`` None: the policy."""

    def __init__(self, problem, policy, n: int, kind: str | None, com_height_m: float,
                 **opt: float) -> None:
        self.p, self.pol, self.kind, self.opt = problem, policy, kind, opt
        m, pose = problem.robot.model, np.asarray(problem.robot.pose, float)
        self.acts = [m.actuator(int(c)).name for c in problem.sim.columns]
        names = list(problem.obs_names)
        self.g = [names.index(f"gravity:{a}") for a in "xyz"]
        self.w = [names.index(f"gyro:{a}") for a in "xy"]
        self.q = {s: np.array([pose[m.actuator(s + j).id] for j in LEG]) for s in "LR"}
        self.foot = {s: leg_fk(self.q[s], s == "L") for s in "LR"}
        self.cols = {s: [self.acts.index(s + j) for j in LEG[1:]] for s in "LR"}
        self.h, self.w0 = com_height_m, np.sqrt(9.81 / com_height_m)
        self.t = np.full(n, -1.0)
        self.d = np.zeros((n, 2))
        self.dt = problem.cfg.control_period_s
        self.params = np.tile(policy.params, (n, 1))
        self.mean, self.std = np.tile(policy.obs_mean, (n, 1)), np.tile(policy.obs_std, (n, 1))

    def __call__(self, rows: np.ndarray, obs: np.ndarray) -> np.ndarray:
        a = self.p.policy.act(self.params[rows], obs, self.mean[rows], self.std[rows])
        if self.kind is None:
            return a
        o = self.opt
        xi = self.h * np.stack([obs[:, self.g[0]] + obs[:, self.w[1]] / self.w0,
                                obs[:, self.g[1]] - obs[:, self.w[0]] / self.w0], axis=1)
        go = (self.t[rows] < 0) & (xi[:, 0] < -o["thr"])
        self.t[rows[go]] = 0.0
        self.d[rows[go]] = np.clip(o.get("gain", 0.0) * xi[go], -0.2, 0.2)
        on = np.flatnonzero(self.t[rows] >= 0)
        if on.size:
            r = rows[on]
            a = a.copy()
            if self.kind == "step":
                for side, q in self._step(r, obs[on][:, self.g]).items():
                    if side == "R" and o.get("keep"):  # the policy's action + the shift
                        a[np.ix_(on, self.cols[side])] += q
                    else:  # the leg follows the reflex alone
                        a[np.ix_(on, self.cols[side])] = q
            else:
                s = np.clip(self.t[r] / o["ramp_s"], 0, 1) * np.clip((0.6 - self.t[r]) / 0.3 + 1,
                                                                    0, 1)
                for side in "LR":
                    a[on, self.acts.index(side + "HipPitch")] += o["hip"] * s
                    a[on, self.acts.index(side + "AnklePitch")] += o["ankle"] * s
            self.t[r] += self.dt
        return a

    def _step(self, r: np.ndarray, g: np.ndarray) -> dict[str, np.ndarray]:
        """The left leg's offsets (HipRoll..AnkleRoll) from the nominal pose along the step,
        and with a shift the right leg's (its offsets, or with ``keep`` only the shift's
        change, added to the policy's action): the body first shifts
        ``shift_m`` over the right foot in ``shift_s``, then the left foot swings."""
        o = self.opt
        shift_s, shift_m = o.get("shift_s", 0.0), o.get("shift_m", 0.0)
        u = np.clip(self.t[r] / shift_s, 0, 1) if shift_s > 0 else np.ones(len(r))
        s = np.clip((self.t[r] - shift_s) / o["swing_s"], 0, 1)
        Q = level(g)

        def solve(side: str, shift: float, step: bool) -> np.ndarray:
            p = np.tile(self.foot[side][0], (len(r), 1))
            p[:, 1] += shift * (u * u * (3 - 2 * u))
            if step:
                p[:, :2] += self.d[r] * (s * s * (3 - 2 * s))[:, None]
                p[:, 2] += o["lift"] * np.sin(np.pi * s)
            hip = hip_position(side == "L")
            p = (Q @ (p - hip)[..., None])[..., 0] + hip
            return leg_ik(p, Q @ self.foot[side][1], side == "L")[:, 1:]

        out = {"L": solve("L", shift_m, True) - self.q["L"][1:]}
        if shift_m:
            out["R"] = solve("R", shift_m, False) - (solve("R", 0.0, False) if o.get("keep")
                                                      else self.q["R"][1:])
        return out


def nominal_step(problem, policy, com_height_m: float, dx_m: float = -0.08,
                 **opt: float) -> str:
    """The step reflex fired at once in the nominal world, no push, with a fixed ``dx_m``
    step: how high the left sole rose (above its start, max over 1 s) and where both
    ankles ended (x, m): does the commanded step leave the floor?"""
    import mujoco

    run = Reflex(problem, policy, 1, "step", com_height_m, **{
        "thr": -1e9, "gain": 0.0, "swing_s": 0.25, "lift": 0.02, **opt})
    call = run.__call__

    def fixed(rows: np.ndarray, obs: np.ndarray) -> np.ndarray:
        first = run.t[rows] < 0
        a = call(rows, obs)
        run.d[rows[first]] = (dx_m, 0.0)
        return a

    res = problem.sim.run(fixed, 1, int(round(3.0 / problem.dt)), record_states=True)
    m = problem.robot.model
    d = mujoco.MjData(m)
    feet = []
    for st in np.asarray(res.states)[0]:
        mujoco.mj_setState(m, d, st, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        mujoco.mj_kinematics(m, d)
        feet.append([d.xpos[m.body(b).id].copy() for b in ("LFoot", "RFoot")])
    f = np.array(feet)
    lift = f[: int(round(1.0 / problem.cfg.control_period_s)) + 1, 0, 2].max() - f[0, 0, 2]
    text = ", ".join(f"{k} {v:g}" for k, v in opt.items())
    return (f"nominal world, step {dx_m:g} m commanded at once ({text or 'no shift'}): "
            "left sole rose "
            f"{1000 * lift:.1f} mm; ankles x {f[0, 0, 0]:+.3f} / {f[0, 1, 0]:+.3f} m -> "
            f"{f[-1, 0, 0]:+.3f} / {f[-1, 1, 0]:+.3f} m after 3 s (left / right); fell: "
            f"{bool(res.fell[0])}")


def survival(problem, run: Reflex, worlds, back: np.ndarray, plain: np.ndarray | None = None
             ) -> tuple[str, ...]:
    """Survival in all worlds and the backward ones, seconds from the push to the fall of the
    backward falls; where the reflex fired, survival with it and (``plain``: the policy's
    falls) without it."""
    res = problem.sim.run(run, worlds, problem.nstep)
    fell = np.asarray(res.fell, bool)
    push_t = np.array([w.push_time_s for w in worlds])
    gone = fell & back
    t_fall = float(np.mean(res.fall_time_s[gone] - push_t[gone])) if gone.any() else np.nan
    fired = run.t >= 0
    out = (f"{100 * (~fell).mean():.0f} %", f"{100 * (~fell[back]).mean():.0f} %",
           f"{t_fall:.2f}")
    if plain is None or not fired.any():
        return out + ("-", "-")
    return out + (f"{int(fired.sum())} ({int(fired[back].sum())} backward)",
                  f"{100 * (~fell[fired]).mean():.0f} / {100 * (~plain[fired]).mean():.0f} %")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", type=Path, help="a humanoid-balance run folder (the NAO)")
    ap.add_argument("--worlds", type=int, default=100)
    ap.add_argument("--push", type=float, default=4.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--com-height", type=float, default=0.242,
                    help="the stance's centre-of-mass height (m; docs/humanoid-balance.md)")
    a = ap.parse_args()
    problem, policy, _ = load_run(a.run)
    if problem.robot.name != "nao":
        sys.exit(f"{a.run}: the probe's leg IK is the NAO's; this run is {problem.robot.name}")
    seeds = eval_seeds(a.worlds, a.seed)
    worlds = problem.worlds(seeds, push_range(problem.robot, a.push, a.push)[0])
    vec = np.array([w.push_ns for w in worlds])
    back = np.abs(np.degrees(np.arctan2(vec[:, 1], vec[:, 0]))) > 135
    n = len(worlds)
    ref = problem.play(np.tile(policy.params, (n, 1)), np.tile(policy.obs_mean, (n, 1)),
                       np.tile(policy.obs_std, (n, 1)), seeds,
                       push_range(problem.robot, a.push, a.push)[0]).result
    own = problem.sim.run(Reflex(problem, policy, n, "step", a.com_height, thr=1e9, gain=1.0,
                                 swing_s=0.2, lift=0.02), worlds, problem.nstep)
    if not (np.array_equal(ref.fell, own.fell) and np.array_equal(ref.torso, own.torso)):
        sys.exit("self-check failed: the untriggered probe differs from the policy's own run")
    print(f"self-check: the untriggered probe equals compare's run ({n} worlds)")
    print(nominal_step(problem, policy, a.com_height))
    for keep in (0, 1):
        print(nominal_step(problem, policy, a.com_height, shift_s=0.2, shift_m=0.04, keep=keep))
    print(f"{n} worlds, push {a.push:g} N s, {int(back.sum())} from the front\n")
    print("| reflex | settings | survival | backward | backward falls: s after the push | "
          "fired in (worlds) | there: survival with / without |")
    print("|---|---|---|---|---|---|---|")
    plain = np.asarray(ref.fell, bool)
    rows = [("none", None, {})] + [("step", "step", s) for s in STEP] + \
        [("hip", "hip", s) for s in HIP]
    for name, kind, opt in rows:
        run = Reflex(problem, policy, n, kind, a.com_height, **opt)
        cells = survival(problem, run, worlds, back, plain if kind else None)
        text = ", ".join(f"{k} {v:g}" for k, v in opt.items()) or "-"
        print(f"| {name} | {text} | " + " | ".join(cells) + " |", flush=True)
    problem.sim.close()


if __name__ == "__main__":
    main()
