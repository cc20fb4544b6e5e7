"""Which pushes can a NAO stepping at the walk's pace catch at all? An estimate from the linear
inverted pendulum's capturability, with the NAO model's mass, CoM height and soles.

    python benchmarks/push_capturability.py [--steps 0.24 0.18 0.15 0.12] [--push-max 5]

Model (Koolen, Pratt et al., "Capturability-based analysis and control of legged locomotion,
Part 1", IJRR 31(9), 2012, the 3D-LIPM with a finite-sized foot): the CoM at height ``z``
moves as ``ẍ = ω² (x − p)``, ``ω = √(g / z)``, with the centre of pressure ``p`` anywhere on
the stance sole; a step ends every ``Δt`` s and moves the ankle by at most ``l`` along an
axis. The instantaneous capture point's distance ``d`` from the stance ankle (along an axis,
towards the sole's edge at ``r`` from the ankle) is then capturable in ``N`` steps iff
``d ≤ d_N`` with

    d_0 = r,    d_N = (d_{N−1} − r + l) e^{−ω Δt} + r,
    d_∞ = l e^{−ω Δt} / (1 − e^{−ω Δt}) + r.

A push ``J`` (N s) on the whole robot of mass ``m`` changes the CoM velocity by ``J / m`` and
puts the capture point ``J / (m ω)`` beyond the CoM. Assumptions that favour the robot:
infinitely many steps; each axis alone (a push is caught if both of its components are: the
reachable steps taken as a box); the same reach ``l`` forward, backward and sideways, no leg
crossing considered (a push towards the stance leg's side would need the other foot to cross,
or two steps); the centre of pressure at the sole's edge (the model's ankle pitch torque
limit, 6.4 N m, allows it: ``m g r`` ≤ 5.7 N m from the ankle). Along x the CoM is where the
nominal pose has it (5 mm ahead of the ankles), with none of the gait's sway. Either way:
sideways, the CoM over the stance ankle and the sole's outer edge beyond it, for either
direction (in the gait the CoM is inboard of the stance ankle, 0.079 m in the nominal double
support: more room against a push towards the stance side, less towards the swing side); the
first step landing ``Δt`` after the push with the full reach (a swing under way may land
sooner, but with less reach). Two reaches: one leg's ``√((L1 + L2)² − h²)`` at the walk's
hip height ``h`` (the swing leg stretched, the stance leg under the body) and twice that (both
legs stretched, the loosest). What the model leaves out can favour the
robot too (the legs' compliance and the feet's friction take some of the push; the torso
turns): an estimate, not a bound. ``benchmarks/walk_capture_step.py`` measures the engine
stepping to the capture point.

Output: a markdown table, one row per reach and step time: the largest capturable push
forward, backward and sideways (N s), the share of directions in which a push of 2, 3, 4 and
5 N s is capturable, and of pushes ``U(0, push-max)`` N s in a uniform random direction (the
walk's training and ``compare`` draw); then the longest step time at which 95 % of those are caught.
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from markdown_table import markdown_table

G = 9.81


def d_infinity(r: float, reach: float, omega: float, dt: float) -> float:
    """``d_∞`` (m): the largest capturable capture-point distance (module doc, ``l`` the
    ``reach``)."""
    e = math.exp(-omega * dt)
    return reach * e / (1.0 - e) + r  # the fixed point of d = (d - r + reach) e + r


def nao_geometry() -> dict:
    """Mass (kg), CoM height (m), the sole's edges from the CoM (m) and the leg's reach (m) of
    the NAO model in the walk's nominal pose (``humanoid-walk``'s start)."""
    import mujoco

    from evomotion.sim.robots.nao.constants import THIGH_M, TIBIA_M
    from evomotion.sim.state import QPOS_OFFSET
    from evomotion.studies.humanoid_omniwalk.problem import OmniWalkConfig, OmniWalkProblem

    cfg = OmniWalkConfig(duration_s=0.1, perturb=False, threads=1)
    p = OmniWalkProblem(cfg)
    m = p.robot.model
    d = mujoco.MjData(m)
    d.qpos[:] = p.ctl.state0[QPOS_OFFSET:QPOS_OFFSET + m.nq]
    mujoco.mj_forward(m, d)
    p.sim.close()
    sole = m.geom("l_sole")  # a box in the foot's (ankle's) frame
    centre, half = m.geom_pos[sole.id], m.geom_size[sole.id]
    com = d.subtree_com[1]
    ankle = d.body("LFoot").xpos  # the foot body's origin is the ankle joint
    ahead = com[0] - ankle[0]  # the CoM ahead of the ankles in the nominal pose
    h = cfg.leg_height_m
    return {
        "mass_kg": float(m.body_subtreemass[1]),
        "com_height_m": float(com[2]),
        "front_m": float(centre[0] + half[0] - ahead),
        "back_m": float(half[0] - centre[0] + ahead),
        "outer_m": float(centre[1] + half[1]),  # the left sole's outer edge from its ankle
        "reach_m": float(math.sqrt((THIGH_M + TIBIA_M) ** 2 - h ** 2)),  # one leg
        "step_s": float(cfg.period_s / 2.0),
    }


def largest_push(j: dict, n: int = 3600) -> np.ndarray:
    """``J_max(θ)`` (N s) over ``n`` directions: both components of the push caught."""
    theta = np.linspace(-math.pi, math.pi, n, endpoint=False)
    c, s = np.cos(theta), np.sin(theta)
    with np.errstate(divide="ignore"):
        jx = np.where(c >= 0, j["front"], j["back"]) / np.abs(c)
        return np.minimum(jx, j["outer"] / np.abs(s))


def caught(geo: dict, legs: int, dt: float) -> dict:
    """The largest push (N s) caught forward, backward and sideways."""
    m, reach = geo["mass_kg"], legs * geo["reach_m"]
    omega = math.sqrt(G / geo["com_height_m"])
    return {k: d_infinity(geo[f"{k}_m"], reach, omega, dt) * m * omega
            for k in ("front", "back", "outer")}


def uniform_share(geo: dict, legs: int, dt: float, push_max: float) -> float:
    """The share of pushes ``U(0, push_max)`` N s in a uniform direction caught."""
    return float(np.minimum(1.0, largest_push(caught(geo, legs, dt)) / push_max).mean())


def step_time_for(geo: dict, legs: int, share: float, push_max: float) -> float:
    """The longest step time (s, searched in 0.001-1 s) at which ``share`` of ``U(0,
    push_max)`` pushes are caught (bisection: the share falls as the step time grows)."""
    lo, hi = 1e-3, 1.0
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if uniform_share(geo, legs, mid, push_max) >= share else (lo, mid)
    return lo


def table(geo: dict, legs: int, dt: float, push_max: float,
          pushes=(2.0, 3.0, 4.0, 5.0)) -> list[str]:
    """One row: ``legs`` (1 or 2) legs' reach, step time ``dt`` (s)."""
    reach = legs * geo["reach_m"]
    j = caught(geo, legs, dt)
    jmax = largest_push(j)
    share = [f"{(jmax >= p).mean():.0%}" for p in pushes]
    uniform = uniform_share(geo, legs, dt, push_max)
    return [f"{reach:.3f} ({legs} leg{'s' if legs > 1 else ''})", f"{dt:.2f}",
            *(f"{j[k]:.1f}" for k in ("front", "back", "outer")),
            *share, f"{uniform:.0%}"]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=float, nargs="+", default=None,
                    help="step times Δt (s); default: the walk's (half its period), 0.18, "
                         "0.15, 0.12")
    ap.add_argument("--push-max", type=float, default=5.0, help="pushes U(0, this) N s")
    a = ap.parse_args(argv)
    if a.push_max <= 0 or (a.steps is not None and min(a.steps) <= 0):
        ap.error("expected --push-max > 0 and step times > 0 s")
    geo = nao_geometry()
    steps = a.steps or [geo["step_s"], 0.18, 0.15, 0.12]
    omega = math.sqrt(G / geo["com_height_m"])
    print(f"NAO model: mass {geo['mass_kg']:.2f} kg, CoM {geo['com_height_m']:.3f} m high "
          f"(ω {omega:.2f} 1/s), sole edges from the CoM: front {geo['front_m']:.3f}, back "
          f"{geo['back_m']:.3f}, outer {geo['outer_m']:.3f} m (from the ankle, the CoM over it)"
          f"; one leg's reach "
          f"{geo['reach_m']:.3f} m; the walk steps every {geo['step_s']:.2f} s")
    head = ["step reach (m)", "step time (s)", "forward (N s)", "backward", "sideways",
            "2 N s", "3 N s", "4 N s", "5 N s", f"U(0, {a.push_max:g}) N s"]
    print(markdown_table(head, [table(geo, legs, dt, a.push_max) for legs in (1, 2)
                                for dt in steps]))
    print(f"95 % of pushes U(0, {a.push_max:g}) N s caught at steps of at most "
          f"{step_time_for(geo, 1, 0.95, a.push_max):.3f} s (one leg's reach), "
          f"{step_time_for(geo, 2, 0.95, a.push_max):.3f} s (both legs')")
    return 0


if __name__ == "__main__":
    sys.exit(main())
