"""Closed-form NAO leg kinematics (paper 002, section 3.3), vectorised over poses.

Chain (NAO H25 published geometry, :mod:`evomotion.sim.robots.nao.constants`, torso frame, metres):
hip joint centre at ``H = (0, ±0.050, -0.085)``; hip yaw-pitch about the axis
``(0, 1/√2, ∓1/√2)`` (upper sign left), i.e. ``R_axis(q0) = Rx(∓π/4) Ry(q0) Rx(±π/4)``; hip roll
(x), hip pitch (y); thigh ``L1 = 0.100`` down; knee pitch; tibia ``L2 = 0.1029`` down; ankle
pitch, ankle roll. The foot pose is the ankle-joint position ``p`` and the foot orientation
``R`` in the torso frame.

Inverse kinematics follows the standard geometric construction used for the NAO (Graf, Härtl,
Röfer, Laue, "A Robust Closed-Loop Gait for the Standard Platform League Humanoid", 2009; the
paper's eqs. for the foot pose relative to the hip and the thigh/shank triangle): express the
hip in the ankle frame -> ankle roll; the thigh-shank triangle -> knee (law of cosines); the
planar angle -> ankle pitch; the remaining hip rotation ``Rx(±π/4) R Rx(-q5) Ry(-(q3+q4)) =
Ry(q0) Rx(q1 ± π/4) Ry(q2)`` -> hip yaw-pitch, roll, pitch (Y-X-Y Euler angles). Knee >= 0 is
the branch chosen. The formulas were checked against MuJoCo FK (see the tests).
"""

from __future__ import annotations

import numpy as np

from evomotion.sim.robots.nao.constants import HIP_OFFSET_Y_M, HIP_OFFSET_Z_M, THIGH_M, TIBIA_M

__all__ = ["THIGH_M", "TIBIA_M", "ankle_position", "hip_position", "leg_fk", "leg_ik", "rot_x",
           "rot_y", "rot_z"]


def _rotation(a: np.ndarray | float, axis: int) -> np.ndarray:
    """Rotation matrices ``[..., 3, 3]`` about ``axis`` (0, 1, 2: x, y, z) by angles ``a``,
    filled in place (the same numbers as stacking their rows, several times quicker)."""
    a = np.asarray(a, dtype=float)
    c, s = np.cos(a), np.sin(a)
    i, j = (axis + 1) % 3, (axis + 2) % 3
    R = np.zeros(a.shape + (3, 3))
    R[..., axis, axis] = 1.0
    R[..., i, i] = c
    R[..., i, j] = -s
    R[..., j, i] = s
    R[..., j, j] = c
    return R


def rot_x(a: np.ndarray | float) -> np.ndarray:
    """Rotation matrices about x, shape ``[..., 3, 3]``."""
    return _rotation(a, 0)


def rot_y(a: np.ndarray | float) -> np.ndarray:
    """Rotation matrices about y, shape ``[..., 3, 3]``."""
    return _rotation(a, 1)


def rot_z(a: np.ndarray | float) -> np.ndarray:
    """Rotation matrices about z, shape ``[..., 3, 3]``."""
    return _rotation(a, 2)


def _constant(a: np.ndarray) -> np.ndarray:
    """``a``, read-only (a module constant)."""
    a.setflags(write=False)
    return a


#: ``(Rx(-s π/4), Rx(s π/4))`` by side sign ``s`` (+1 left): the hip yaw-pitch axis's tilt
_TILT = {s: (_constant(rot_x(-s * np.pi / 4)), _constant(rot_x(s * np.pi / 4)))
         for s in (1.0, -1.0)}
_DOWN = _constant(np.array([0.0, 0.0, -1.0]))


def hip_position(left: bool) -> np.ndarray:
    """Hip joint centre ``[3]`` in the torso frame (m)."""
    return np.array([0.0, HIP_OFFSET_Y_M if left else -HIP_OFFSET_Y_M, -HIP_OFFSET_Z_M])


def leg_fk(q: np.ndarray, left: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Ankle position ``[..., 3]`` and foot rotation ``[..., 3, 3]`` (torso frame) of joint
    vectors ``q[..., 6]`` = (HipYawPitch, HipRoll, HipPitch, KneePitch, AnklePitch, AnkleRoll)."""
    q = np.asarray(q, dtype=float)
    ankle, R_knee = _ankle(q, left)
    return ankle, R_knee @ rot_y(q[..., 4]) @ rot_x(q[..., 5])


def ankle_position(q: np.ndarray, left: bool = True) -> np.ndarray:
    """:func:`leg_fk`'s ankle position alone (the same numbers, without the foot's
    rotation: what leg odometry needs)."""
    return _ankle(np.asarray(q, dtype=float), left)[0]


def _ankle(q: np.ndarray, left: bool) -> tuple[np.ndarray, np.ndarray]:
    """The ankle's position ``[..., 3]`` and the shank's rotation ``[..., 3, 3]`` of float
    joint vectors ``q[..., 6]`` (:func:`leg_fk`)."""
    tilt, untilt = _TILT[1.0 if left else -1.0]
    R_hip = tilt @ rot_y(q[..., 0]) @ untilt @ rot_x(q[..., 1]) @ rot_y(q[..., 2])
    knee = hip_position(left) + THIGH_M * (R_hip @ _DOWN)
    R_knee = R_hip @ rot_y(q[..., 3])
    return knee + TIBIA_M * (R_knee @ _DOWN), R_knee


def leg_ik(p: np.ndarray, R: np.ndarray, left: bool = True) -> np.ndarray:
    """Joint angles ``[..., 6]`` putting the ankle at ``p[..., 3]`` with foot rotation
    ``R[..., 3, 3]`` (torso frame). Unreachable distances are clipped to the stretched leg."""
    p = np.asarray(p, dtype=float)
    R = np.asarray(R, dtype=float)
    s = 1.0 if left else -1.0
    Rt = np.swapaxes(R, -1, -2)
    v = (Rt @ (hip_position(left) - p)[..., None])[..., 0]  # hip seen from the ankle frame
    q5 = np.arctan2(v[..., 1], v[..., 2])
    q5 = np.where(q5 > np.pi / 2, q5 - np.pi, np.where(q5 <= -np.pi / 2, q5 + np.pi, q5))
    d2 = np.sum(v * v, axis=-1)
    cos_knee = (d2 - THIGH_M**2 - TIBIA_M**2) / (2 * THIGH_M * TIBIA_M)
    q3 = np.arccos(np.clip(cos_knee, -1.0, 1.0))
    u = (rot_x(q5) @ v[..., None])[..., 0]
    w_x, w_z = -THIGH_M * np.sin(q3), TIBIA_M + THIGH_M * np.cos(q3)
    q4 = np.arctan2(w_x, w_z) - np.arctan2(u[..., 0], u[..., 2])
    q4 = (q4 + np.pi) % (2 * np.pi) - np.pi
    M = _TILT[s][1] @ R @ rot_x(-q5) @ rot_y(-(q3 + q4))
    b = np.arctan2(s * np.hypot(M[..., 1, 0], M[..., 1, 2]), M[..., 1, 1])
    q0 = np.arctan2(s * M[..., 0, 1], s * M[..., 2, 1])
    q1 = b - s * np.pi / 4
    q2 = np.arctan2(s * M[..., 1, 0], -s * M[..., 1, 2])
    return np.stack([q0, q1, q2, q3, q4, q5], axis=-1)
