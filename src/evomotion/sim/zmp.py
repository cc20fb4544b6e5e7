"""ZMP stability check from simulated contact forces (paper 002, step 5; the kick study and the
studio's motion analysis use it).

On flat ground the zero-moment point equals the centre of pressure (CoP) of the vertical
ground-reaction forces (Vukobratović & Borovac, "Zero-Moment Point — Thirty Five Years of its
Life", Int. J. Humanoid Robotics 1(1), 2004; Sardain & Bessonnet, IEEE T-SMC-A 34(5), 2004)::

    p_CoP = sum_i f_z,i p_i / sum_i f_z,i

over the contact points ``p_i`` with the floor; MuJoCo gives each contact force exactly
(``mj_contactForce``, contact frame with the normal first). The support polygon is the convex
hull of the contact points (Andrew's monotone chain); the stability margin is the signed
distance of the CoP to the hull boundary (positive inside). Lengths in metres, forces in N.
"""

from __future__ import annotations

import mujoco
import numpy as np


def floor_contacts(model: mujoco.MjModel, data: mujoco.MjData, floor_geom: int,
                   bodies: set[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """World positions ``[k, 3]`` and world forces ``[k, 3]`` (on the body, from the floor)
    of the ``k`` active contacts that involve ``floor_geom`` (and, with ``bodies``, a geom
    of one of those bodies: the robot's feet, not a ball on the same floor)."""
    pos, force = [], []
    f6 = np.zeros(6)
    for i in range(data.ncon):
        c = data.contact[i]
        if floor_geom not in (c.geom1, c.geom2):
            continue
        other = c.geom2 if c.geom1 == floor_geom else c.geom1
        if bodies is not None and int(model.geom_bodyid[other]) not in bodies:
            continue
        mujoco.mj_contactForce(model, data, i, f6)
        fw = c.frame.reshape(3, 3).T @ f6[:3]  # force of geom1 on geom2, world frame
        sign = 1.0 if c.geom1 == floor_geom else -1.0
        pos.append(np.array(c.pos))
        force.append(sign * fw)
    if not pos:
        return np.zeros((0, 3)), np.zeros((0, 3))
    return np.array(pos), np.array(force)


def centre_of_pressure(pos: np.ndarray, force: np.ndarray) -> tuple[np.ndarray, float]:
    """CoP ``[2]`` (x, y) and total normal force (N); NaN CoP when nothing is loaded."""
    fz = np.abs(force[:, 2]) if len(force) else np.zeros(0)
    total = float(fz.sum())
    if total <= 0:
        return np.full(2, np.nan), 0.0
    return (fz[:, None] * pos[:, :2]).sum(0) / total, total


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise hull vertices ``[h, 2]`` of 2-D points (monotone chain)."""
    pts = np.unique(np.round(np.asarray(points, dtype=float)[:, :2], 12), axis=0)
    if len(pts) < 3:
        return pts

    def cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list[np.ndarray] = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    upper: list[np.ndarray] = []
    for p in pts[::-1]:
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1])


def support_margin(point: np.ndarray, hull: np.ndarray) -> float:
    """Signed distance (m) of ``point`` to the boundary of the CCW polygon ``hull``:
    positive inside, negative outside; ``-inf`` for a degenerate polygon (< 3 vertices)."""
    if len(hull) < 3 or not np.all(np.isfinite(point)):
        return -np.inf
    a = hull
    b = np.roll(hull, -1, axis=0)
    edge = b - a
    length = np.linalg.norm(edge, axis=1)
    rel = point - a
    # inward normal of a CCW polygon is (-ey, ex); signed distance to each edge line
    signed = (edge[:, 0] * rel[:, 1] - edge[:, 1] * rel[:, 0]) / length
    inside = bool(np.all(signed >= 0))
    t = np.clip(np.einsum("ij,ij->i", rel, edge) / length**2, 0.0, 1.0)
    dist = np.min(np.linalg.norm(rel - t[:, None] * edge, axis=1))
    return float(dist if inside else -dist)


def zmp_margin(model: mujoco.MjModel, data: mujoco.MjData, floor_geom: int) -> float:
    """Margin of the contact CoP inside the support polygon of the current MuJoCo state."""
    pos, force = floor_contacts(model, data, floor_geom)
    cop, total = centre_of_pressure(pos, force)
    if total <= 0:
        return -np.inf
    return support_margin(cop, convex_hull(pos[:, :2]))
