"""What a played motion does, frame by frame, for the plots under the 3D player (issue 35's
motion analysis): every hinge joint's angle, the torso's tilt and height, the centre of mass,
which feet touch the floor, and the ZMP (the centre of pressure of the robot's floor contacts,
``sim/zmp.py``; on flat ground they are the same point).

Computed from the same recorded frames the player shows (the full states of the physics
replay and the servo targets of the step after each): one ``mj_forward`` per frame gives the
centre of mass (``subtree_com`` of the robot's root body), the contacts (a foot touches when a
contact of one of its geoms is within :data:`TOUCH_M` of closing) and their forces.
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

TOUCH_M = 0.002  # a contact this close (m) counts as a touch


def _root_body(model: mujoco.MjModel) -> int:
    free = np.flatnonzero(model.jnt_type == mujoco.mjtJoint.mjJNT_FREE)
    return int(model.jnt_bodyid[free[0]]) if free.size else 1


def traces(model: mujoco.MjModel, states: np.ndarray, ctrl: np.ndarray,
           feet: dict[str, str]) -> dict[str, Any]:
    """Per frame of the full states ``states[F, ns]`` under the servo targets ``ctrl[F, nu]``,
    one ``mj_forward`` each: ``joints`` {name: deg}, ``tilt_deg``, ``torso_z_m``, ``com_m``
    [F, 3], ``contact`` {foot: 0/1} (``feet`` maps a foot's name to its body) and ``zmp_m``
    [F, 2] (x, y; NaN while no foot carries load; only the robot's contacts with the floor
    plane count, not a ball's)."""
    from evomotion.sim.state import STATE_SPEC
    from evomotion.sim.zmp import centre_of_pressure, floor_contacts

    data = mujoco.MjData(model)
    root = _root_body(model)
    robot = set(np.flatnonzero(model.body_rootid == model.body_rootid[root]).tolist())
    planes = np.flatnonzero(model.geom_type == mujoco.mjtGeom.mjGEOM_PLANE)
    hinge = [j for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE
             and model.jnt_bodyid[j] != 0 and mujoco.mj_id2name(
                 model, mujoco.mjtObj.mjOBJ_JOINT, j)]
    foot_body = {f: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b)
                 for f, b in feet.items()}
    foot_body = {f: b for f, b in foot_body.items() if b >= 0}
    n = len(states)
    qpos, com, tilt, z = np.empty((n, model.nq)), np.empty((n, 3)), np.empty(n), np.empty(n)
    zmp = np.full((n, 2), np.nan)
    contact = {f: np.zeros(n) for f in foot_body}
    for k, (state, u) in enumerate(zip(states, ctrl, strict=True)):
        mujoco.mj_setState(model, data, state, STATE_SPEC)
        data.ctrl[:] = u
        mujoco.mj_forward(model, data)
        qpos[k], com[k] = data.qpos, data.subtree_com[root]
        up = data.xmat[root].reshape(3, 3)[2, 2]
        tilt[k], z[k] = np.degrees(np.arccos(np.clip(up, -1.0, 1.0))), data.xpos[root][2]
        for c in data.contact[:data.ncon]:
            if c.dist > TOUCH_M:
                continue
            bodies = {int(model.geom_bodyid[c.geom1]), int(model.geom_bodyid[c.geom2])}
            for f, b in foot_body.items():
                if b in bodies:
                    contact[f][k] = 1.0
        if planes.size:
            pos, force = floor_contacts(model, data, int(planes[0]), robot)
            zmp[k] = centre_of_pressure(pos, force)[0]
    joints = {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j):
              np.degrees(qpos[:, model.jnt_qposadr[j]]) for j in hinge}
    return {"joints": joints, "tilt_deg": tilt, "torso_z_m": z, "com_m": com,
            "contact": contact, "zmp_m": zmp}


def balance_series(tr: dict[str, Any], t: np.ndarray) -> list[dict]:
    """ZMP and CoM, x and y (m), against time."""
    out, zmp = [], tr["zmp_m"]
    for name, v in (("ZMP x", zmp[:, 0]), ("CoM x", tr["com_m"][:, 0]), ("ZMP y", zmp[:, 1]),
                    ("CoM y", tr["com_m"][:, 1])):
        pts = [[float(a), None if not np.isfinite(b) else round(float(b), 4)]
               for a, b in zip(t, v, strict=True)]
        out.append({"name": f"{name} (m)", "type": "line", "showSymbol": False, "data": pts,
                    "lineStyle": {"type": "dashed"} if name.startswith("CoM") else {}})
    return out


def angle_series(tr: dict[str, Any], t: np.ndarray) -> dict[str, list]:
    """Every angle the player can plot (deg): the torso's tilt and each joint, as ECharts
    ``[[t, value], ...]``."""
    out = {"torso tilt": tr["tilt_deg"], **tr["joints"]}
    return {k: np.round(np.stack([t, v], 1), 3).tolist() for k, v in out.items()}


def support_series(tr: dict[str, Any], t: np.ndarray) -> list[dict]:
    """Foot contacts as steps (foot i drawn at i + contact x 0.8) and the torso's height and
    centre of mass height (m, second axis)."""
    series = []
    for i, (foot, on) in enumerate(sorted(tr["contact"].items())):
        series.append({"name": f"{foot} foot on the floor", "type": "line", "step": "end",
                       "showSymbol": False, "yAxisIndex": 0,
                       "data": np.round(np.stack([t, i + 0.8 * on], 1), 3).tolist()})
    for name, v in (("torso height (m)", tr["torso_z_m"]), ("CoM height (m)", tr["com_m"][:, 2])):
        series.append({"name": name, "type": "line", "showSymbol": False, "yAxisIndex": 1,
                       "data": np.round(np.stack([t, v], 1), 4).tolist()})
    return series
