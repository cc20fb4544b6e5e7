"""Why the pushes from the front fell the balance policy (issue 33): the kinetic energy a push
gives the NAO standing in humanoid-balance's stance, beside the energy it takes to tip its
centre of mass over the edge of the support polygon in the push's direction.

The NAO (``problem.*`` defaults: the stance, the nominal world) holds its nominal pose on its
position servos for 1 s; then one push of ``--push`` N s on the torso (one physics step, as
the closed loop applies it) in each of four directions. Reported: the kinetic energy right after
it (``0.5 qvel' M qvel``, J), the centre of mass's speed (m/s), and the barrier ``m g
(sqrt(h^2 + d^2) - h)`` (J) of a rigid body tipping about the support edge ``d`` m from the
centre of mass's ground point along the direction (``d`` from the soles' contacts at rest:
where the ray from the centre of mass's ground point along the push leaves the convex hull of
the contact points), ``h`` the centre of mass's height. Energy beyond the
barrier must leave through the joints (the servos' damping, a bending body) or a step, and the
fall rule (the torso tilted 45 degrees) limits how far the body may bend.

    python benchmarks/balance_push_energy.py --push 4 [--lean 0.2]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import mujoco
import numpy as np
from scipy.spatial import ConvexHull

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from evomotion.errors import InputError  # noqa: E402
from evomotion.sim.worlds import torso_id  # noqa: E402
from evomotion.studies.humanoid_balance.problem import (  # noqa: E402
    HumanoidBalanceConfig,
    HumanoidBalanceProblem,
)

DIRECTIONS = {"from behind (pushed forward)": 0.0, "from the front (pushed backward)": 180.0,
              "from the right (pushed left)": 90.0, "from the left (pushed right)": -90.0}


def edge_distance(hull: ConvexHull, origin: np.ndarray, u: np.ndarray) -> float:
    """How far (m) the ray from ``origin`` along ``u`` runs inside the convex ``hull``."""
    n, c = hull.equations[:, :2], hull.equations[:, 2]
    out = n @ u > 0
    return float(np.min(-(n[out] @ origin + c[out]) / (n[out] @ u)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--push", type=float, default=4.0, help="N s")
    ap.add_argument("--lean", type=float, default=0.0,
                    help="problem.stance_lean_rad (rad; the default stance otherwise)")
    a = ap.parse_args()
    try:
        problem = HumanoidBalanceProblem(HumanoidBalanceConfig(stance_lean_rad=a.lean))
    except InputError as e:
        sys.exit(f"--lean {a.lean}: {e}")
    m = problem.robot.model
    d = mujoco.MjData(m)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    mujoco.mj_setState(m, d, problem.robot.state0, spec)
    d.ctrl[:] = problem.sim.nominal
    for _ in range(int(round(1.0 / m.opt.timestep))):
        mujoco.mj_step(m, d)
    rest = np.empty(mujoco.mj_stateSize(m, spec))
    mujoco.mj_getState(m, d, rest, spec)
    mass = float(m.body_subtreemass[0])
    com = d.subtree_com[0].copy()
    feet = {problem.robot.model.body(b).id for b in ("LFoot", "RFoot")}  # the NAO's
    points = np.array([d.contact[i].pos[:2] for i in range(d.ncon)
                       if m.geom_bodyid[d.contact[i].geom1] in feet
                       or m.geom_bodyid[d.contact[i].geom2] in feet])
    print(f"{problem.robot.name} in the stance (lean {a.lean:g} rad): {mass:.2f} kg, centre "
          f"of mass {com[2]:.3f} m high; {len(points)} sole contacts; push {a.push:g} N s on "
          "the torso\n")
    print("| push | kinetic energy after it (J) | centre of mass speed (m/s) | support edge "
          "(m) | tipping barrier (J) | energy / barrier |")
    print("|---|---|---|---|---|---|")
    hull = ConvexHull(points)
    tid = torso_id(m)
    for name, deg in DIRECTIONS.items():
        mujoco.mj_setState(m, d, rest, spec)
        u = np.array([np.cos(np.radians(deg)), np.sin(np.radians(deg))])
        d.xfrc_applied[tid, :2] = u * a.push / m.opt.timestep
        mujoco.mj_step(m, d)
        d.xfrc_applied[:] = 0.0
        mujoco.mj_forward(m, d)
        Mv = np.zeros(m.nv)
        mujoco.mj_mulM(m, d, Mv, d.qvel)
        ke = 0.5 * float(d.qvel @ Mv)
        mujoco.mj_subtreeVel(m, d)
        v = float(np.hypot(*d.subtree_linvel[0][:2]))
        edge = edge_distance(hull, com[:2], u)
        barrier = mass * 9.81 * (np.hypot(com[2], edge) - com[2])
        print(f"| {name} | {ke:.2f} | {v:.2f} | {edge:.3f} | {barrier:.2f} | {ke / barrier:.1f} |")


if __name__ == "__main__":
    main()
