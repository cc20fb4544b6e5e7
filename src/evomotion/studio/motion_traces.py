"""What a played motion does, frame by frame, for the plots under the 3D player (issue 35's
motion analysis): every hinge joint's angle, the torso's tilt and height, the centre of mass,
which feet touch the floor, and the ZMP (the centre of pressure of the robot's floor contacts,
``sim/zmp.py``; on flat ground they are the same point).

Computed from the same recorded frames the player shows (``qpos`` of the physics replay):
``mj_fwdPosition`` per frame gives the centre of mass (``subtree_com`` of the robot's root
body) and the contacts (a foot touches when a contact of one of its geoms is within
:data:`TOUCH_M` of closing).
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

TOUCH_M = 0.002  # a contact this close (m) counts as a touch


def _root_body(model: mujoco.MjModel) -> int:
    free = np.flatnonzero(model.jnt_type == mujoco.mjtJoint.mjJNT_FREE)
    return int(model.jnt_bodyid[free[0]]) if free.size else 1


def traces(model: mujoco.MjModel, qpos: np.ndarray, feet: dict[str, str]) -> dict[str, Any]:
    """Per frame of ``qpos[F, nq]``: ``joints`` {name: deg}, ``tilt_deg``, ``torso_z_m``,
    ``com_m`` [F, 3] and ``contact`` {foot: 0/1}; ``feet`` maps a foot's name to its body."""
    data = mujoco.MjData(model)
    root = _root_body(model)
    hinge = [j for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE
             and model.jnt_bodyid[j] != 0 and mujoco.mj_id2name(
                 model, mujoco.mjtObj.mjOBJ_JOINT, j)]
    foot_body = {f: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b)
                 for f, b in feet.items()}
    foot_body = {f: b for f, b in foot_body.items() if b >= 0}
    n = len(qpos)
    com, tilt, z = np.empty((n, 3)), np.empty(n), np.empty(n)
    contact = {f: np.zeros(n) for f in foot_body}
    for k, q in enumerate(qpos):
        data.qpos[:] = q
        mujoco.mj_fwdPosition(model, data)
        com[k] = data.subtree_com[root]
        up = data.xmat[root].reshape(3, 3)[2, 2]
        tilt[k], z[k] = np.degrees(np.arccos(np.clip(up, -1.0, 1.0))), data.xpos[root][2]
        for c in data.contact[:data.ncon]:
            if c.dist > TOUCH_M:
                continue
            bodies = {int(model.geom_bodyid[c.geom1]), int(model.geom_bodyid[c.geom2])}
            for f, b in foot_body.items():
                if b in bodies:
                    contact[f][k] = 1.0
    joints = {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j):
              np.degrees(qpos[:, model.jnt_qposadr[j]]) for j in hinge}
    return {"joints": joints, "tilt_deg": tilt, "torso_z_m": z, "com_m": com,
            "contact": contact}


def zmp_trace(model: mujoco.MjModel, states: np.ndarray, ctrl: np.ndarray) -> np.ndarray:
    """``[F, 2]`` ZMP (x, y; m) of each frame's full state under its servo targets (NaN while
    no foot carries load); only the robot's contacts with the floor plane count."""
    from evomotion.sim.state import STATE_SPEC
    from evomotion.sim.zmp import centre_of_pressure, floor_contacts

    planes = np.flatnonzero(model.geom_type == mujoco.mjtGeom.mjGEOM_PLANE)
    out = np.full((len(states), 2), np.nan)
    if not planes.size:
        return out
    root = _root_body(model)
    robot = {b for b in range(model.nbody) if b == root or _descends(model, b, root)}
    data = mujoco.MjData(model)
    for k, (state, u) in enumerate(zip(states, ctrl, strict=True)):
        mujoco.mj_setState(model, data, state, STATE_SPEC)
        data.ctrl[:] = u
        mujoco.mj_forward(model, data)
        pos, force = floor_contacts(model, data, int(planes[0]), robot)
        out[k] = centre_of_pressure(pos, force)[0]
    return out


def _descends(model: mujoco.MjModel, body: int, root: int) -> bool:
    while body > 0:
        if body == root:
            return True
        body = int(model.body_parentid[body])
    return False


def balance_series(tr: dict[str, Any], zmp: np.ndarray, t: np.ndarray) -> list[dict]:
    """ZMP and CoM, x and y (m), against time."""
    out = []
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
