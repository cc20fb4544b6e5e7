"""Closed-form leg kinematics of the :mod:`.model` quadruped (metres, radians, torso frame).

A leg is a yaw hinge (vertical axis, at the hip) followed by a planar two-link arm (hip
pitch, knee pitch; thigh ``l1``, shank ``l2``). In the hip frame (the torso frame moved to
the hip and turned by the sector's nominal angle ``nu``) the foot centre of joint angles
``(q0, q1, q2)`` lies at horizontal distance ``r`` along direction ``q0`` and height ``z``::

    r = l1 cos q1 + l2 cos(q1 + q2),    z = -(l1 sin q1 + l2 sin(q1 + q2))

(positive pitch turns a link downwards). Inverse: ``q0 = atan2(y, x)``, and with
``d = |(r, z)|``, ``alpha = atan2(-z, r)`` (the hip-foot line below the horizontal), the law
of cosines gives the hip angle ``gamma`` between thigh and that line and the knee's inner
angle ``kappa``; the knee-up solution is ``q1 = alpha - gamma``, ``q2 = pi - kappa``.
Distances outside the links' reach are clamped (the leg points at the target, stretched or
folded as far as it goes). Everything is vectorised over leading axes.
"""

from __future__ import annotations

import numpy as np

from evomotion.sim.quadruped.geometry import NOMINAL_ANGLES
from evomotion.sim.quadruped.model import QuadrupedSpec

_EPS = 1e-9


def _to_hip(spec: QuadrupedSpec, leg: int, p: np.ndarray) -> np.ndarray:
    nu = NOMINAL_ANGLES[leg]
    c, s = np.cos(nu), np.sin(nu)
    d = np.asarray(p, dtype=float) - spec.hips_m()[leg]
    return np.stack([c * d[..., 0] + s * d[..., 1], -s * d[..., 0] + c * d[..., 1],
                     d[..., 2]], axis=-1)


def _from_hip(spec: QuadrupedSpec, leg: int, h: np.ndarray) -> np.ndarray:
    nu = NOMINAL_ANGLES[leg]
    c, s = np.cos(nu), np.sin(nu)
    out = np.stack([c * h[..., 0] - s * h[..., 1], s * h[..., 0] + c * h[..., 1], h[..., 2]],
                   axis=-1)
    return out + spec.hips_m()[leg]


def leg_fk(spec: QuadrupedSpec, leg: int, q: np.ndarray) -> np.ndarray:
    """Foot-centre position ``[..., 3]`` [m] in the torso frame for joint angles
    ``q[..., 3]`` = (yaw, pitch, knee) [rad] of ``leg``."""
    q = np.asarray(q, dtype=float)
    l1, l2 = spec.thigh_m, spec.shank_m
    q0, q1, q12 = q[..., 0], q[..., 1], q[..., 1] + q[..., 2]
    r = l1 * np.cos(q1) + l2 * np.cos(q12)
    z = -(l1 * np.sin(q1) + l2 * np.sin(q12))
    return _from_hip(spec, leg, np.stack([r * np.cos(q0), r * np.sin(q0), z], axis=-1))


def leg_ik(spec: QuadrupedSpec, leg: int, p: np.ndarray) -> np.ndarray:
    """Joint angles ``[..., 3]`` (yaw, pitch, knee) [rad] putting the foot centre of ``leg``
    at ``p[..., 3]`` [m] (torso frame); NaN in, NaN out."""
    h = _to_hip(spec, leg, p)
    l1, l2 = spec.thigh_m, spec.shank_m
    q0 = np.arctan2(h[..., 1], h[..., 0])
    r = np.hypot(h[..., 0], h[..., 1])
    z = h[..., 2]
    d = np.clip(np.hypot(r, z), abs(l1 - l2) + _EPS, l1 + l2 - _EPS)
    alpha = np.arctan2(-z, r)
    gamma = np.arccos(np.clip((l1 * l1 + d * d - l2 * l2) / (2 * l1 * d), -1.0, 1.0))
    kappa = np.arccos(np.clip((l1 * l1 + l2 * l2 - d * d) / (2 * l1 * l2), -1.0, 1.0))
    return np.stack([q0, alpha - gamma, np.pi - kappa], axis=-1)


def reachable(spec: QuadrupedSpec, leg: int, p: np.ndarray) -> np.ndarray:
    """Whether ``leg``'s links reach ``p[..., 3]`` [m] exactly (no clamping in :func:`leg_ik`)."""
    h = _to_hip(spec, leg, p)
    d = np.linalg.norm(h, axis=-1)
    l1, l2 = spec.thigh_m, spec.shank_m
    return (d >= abs(l1 - l2) + _EPS) & (d <= l1 + l2 - _EPS)


def legs_ik(spec: QuadrupedSpec, feet: np.ndarray) -> np.ndarray:
    """Joint angles ``[..., 12]`` (leg-major, as the actuators) for the four foot centres
    ``feet[..., 4, 3]`` [m] in the torso frame."""
    feet = np.asarray(feet, dtype=float)
    return np.concatenate([leg_ik(spec, i, feet[..., i, :]) for i in range(4)], axis=-1)


def legs_fk(spec: QuadrupedSpec, q: np.ndarray) -> np.ndarray:
    """Foot centres ``[..., 4, 3]`` [m] in the torso frame for ``q[..., 12]``."""
    q = np.asarray(q, dtype=float)
    return np.stack([leg_fk(spec, i, q[..., 3 * i:3 * i + 3]) for i in range(4)], axis=-2)


def sector_point_m(spec: QuadrupedSpec, leg: int, length: float | np.ndarray,
                   offset: float | np.ndarray, lift_m: float | np.ndarray = 0.0) -> np.ndarray:
    """Torso-frame foot centre [m] at sector coordinates: ``length`` [paper units] from the
    hip, ``offset`` [rad] from the nominal angle, ``lift_m`` above the floor."""
    length, offset, lift = np.broadcast_arrays(np.asarray(length, dtype=float) * spec.unit_m,
                                               np.asarray(offset, dtype=float),
                                               np.asarray(lift_m, dtype=float))
    ang = NOMINAL_ANGLES[leg] + offset
    hip = spec.hips_m()[leg]
    return np.stack([hip[0] + length * np.cos(ang), hip[1] + length * np.sin(ang),
                     lift - spec.foot_drop_m], axis=-1)
