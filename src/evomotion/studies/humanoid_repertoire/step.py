"""One NAO step from the ready pose back to the ready pose, displaced by (dx, dy, dtheta).

Why not the joint-space knots of humanoid-step: those drive the 10 leg servos without the hip
yaw-pitch, so a step cannot turn (the contact model no longer lets a foot spin), and 190 genes
are a poor search space for a repertoire of 720 cells. This encoding is the humanoid-step
idea (shift the weight onto the stance leg, then swing) written in Cartesian space through
the closed-form leg IK (:mod:`evomotion.sim.robots.nao.leg_ik`), so every genome is a kinematically
valid step and every cell's motion starts and ends in the same ready pose: repertoire
motions chain without transitions.

Phases (``sigma`` = +1 when the left foot leads): shift the torso by ``sway_m`` over the
stance foot (``shift_s``), swing the lead foot to its new place (``swing_s``, lifted by
``step_height_m``), shift over the lead foot, carrying the torso by the whole displacement
(``shift_s``), swing the other foot beside it (``swing_s``), shift back to the middle
(``shift_s``): the weight is over a standing foot whenever the other is in the air. In the
world, the lead foot ends at ``T(dx, dy, dtheta)`` of its start and so does the other. The
NAO's two hip yaw-pitch joints are one motor, and a leg's IK value of it depends on where its
foot is: the torso's yaw is chosen per key pose (secant iterations from half the feet's yaw)
so that both legs need the same value.
Times are on the 20 ms key-pose grid of a Webots ``.motion``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.joint_limits import JOINT_RANGES
from evomotion.sim.robots.nao.leg_ik import leg_ik, rot_z

#: (name, low, high, default): SI units (m, s, rad); the commanded displacement is in the
#: robot's initial frame
GENES: tuple[tuple[str, float, float, float], ...] = (
    ("dx_m", -0.12, 0.17, 0.0),  # commanded forward displacement of both feet
    ("dy_m", -0.10, 0.10, 0.0),  # commanded leftward displacement
    ("dtheta_rad", -0.90, 0.90, 0.0),  # commanded turn (+ = left)
    ("lead", -1.0, 1.0, 0.5),  # > 0: the left foot swings first
    ("sway_m", 0.0, 0.10, 0.03),  # lateral torso shift over the stance foot
    ("step_height_m", 0.005, 0.05, 0.02),  # swing foot lift
    ("shift_s", 0.20, 0.80, 0.40),  # each weight shift
    ("swing_s", 0.20, 0.80, 0.40),  # each swing
)
NAMES = tuple(g[0] for g in GENES)
LOWER = np.array([g[1] for g in GENES])
UPPER = np.array([g[2] for g in GENES])
DEFAULT = np.array([g[3] for g in GENES])
INDEX = {n: i for i, n in enumerate(NAMES)}

POSE_MS = 20
LEG_HEIGHT_M = 0.155  # ready pose: hip joint to ankle, vertical (the walk's default gait)
WIDTH_M = 0.03  # ready pose: feet this much wider than the hips, each side
HIP_Z_M, HIP_Y_M = nao.HIP_OFFSET_Z_M, nao.HIP_OFFSET_Y_M
_LO, _HI = np.array([JOINT_RANGES[j] for j in nao.JOINTS]).T
_L_COLS = [nao.JOINTS.index(j) for j in nao.LEFT_LEG]
_R_COLS = [nao.JOINTS.index(j) for j in nao.RIGHT_LEG]
MAX_DURATION_S = 3 * UPPER[INDEX["shift_s"]] + 2 * UPPER[INDEX["swing_s"]]


def _ms(s: float) -> int:
    return int(max(1, round(s * 1000 / POSE_MS))) * POSE_MS


def durations_ms(genes: np.ndarray) -> tuple[int, int]:
    """(shift, swing) of one genome in ms, on the pose grid."""
    return _ms(float(genes[INDEX["shift_s"]])), _ms(float(genes[INDEX["swing_s"]]))


def _smooth(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return 0.5 * (1.0 - np.cos(np.pi * x))


def _rot(a: np.ndarray, v: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]], -1)


@dataclass(frozen=True)
class FootPlan:
    """The Cartesian step of one genome on the 20 ms key-pose grid ``t`` [ms]: the torso's
    (hip centre's) ground position ``torso[K, 2]`` and first-guess yaw ``yaw[K]``, each foot's
    ground position ``[K, 2]``, yaw ``[K]`` and lift ``[K]`` (m, rad, in the robot's initial
    frame), for the leading foot (``lead_is_left``) and the other one."""

    t: np.ndarray
    torso: np.ndarray
    yaw: np.ndarray
    lead: tuple[np.ndarray, np.ndarray, np.ndarray]
    other: tuple[np.ndarray, np.ndarray, np.ndarray]
    lead_is_left: bool


def foot_plan(genes: np.ndarray, left0: np.ndarray, right0: np.ndarray,
              durations: tuple[int, int] | None = None) -> FootPlan:
    """The phases of the module doc for feet starting at ground positions ``left0`` and
    ``right0`` [m] (relative to the torso); ``durations`` (shift, swing) [ms] default to the
    genome's on the pose grid."""
    g = {n: float(v) for n, v in zip(NAMES, np.asarray(genes, float), strict=True)}
    sh, sw = durations or durations_ms(np.asarray(genes, float))
    t = np.arange(0, 3 * sh + 2 * sw + 1, POSE_MS, dtype=float)
    sig = 1.0 if g["lead"] >= 0 else -1.0
    b = np.cumsum([0, sh, sw, sh, sw, sh]).astype(float)  # phase boundaries (ms)
    s1 = np.clip((t - b[1]) / sw, 0, 1)  # first swing, linear time
    s2 = np.clip((t - b[3]) / sw, 0, 1)
    u1, u2 = _smooth(s1), _smooth(s2)
    # torso progress along the displacement and its yaw (see the module doc)
    prog = np.where(t < b[3], 0.5 * u1, 0.5 * (1.0 + u2))  # yaw: the first guess
    carry = _smooth((t - b[2]) / sh)  # the torso moves over the lead foot in the mid shift
    d = np.array([g["dx_m"], g["dy_m"]])
    th = g["dtheta_rad"]
    yaw_t = prog * th

    # sway: towards the stance foot (-sig side) during the first swing, then the lead's
    def shift(t0: float) -> np.ndarray:
        return _smooth((t - t0) / sh)

    side = -sig * shift(b[0]) + 2 * sig * shift(b[2]) - sig * shift(b[4])
    sway = g["sway_m"] * side
    torso = carry[:, None] * d + _rot(yaw_t, np.stack([np.zeros_like(t), sway], -1))
    lead0, other0 = (left0, right0) if sig > 0 else (right0, left0)
    lead1, other1 = d + _rot(np.array(th), lead0), d + _rot(np.array(th), other0)
    lead = lead0 + u1[:, None] * (lead1 - lead0)
    other = other0 + u2[:, None] * (other1 - other0)
    h = g["step_height_m"]
    return FootPlan(t, torso, yaw_t, (lead, u1 * th, h * np.sin(np.pi * s1)),
                    (other, u2 * th, h * np.sin(np.pi * s2)), sig > 0)


def poses(genes: np.ndarray) -> np.ndarray:
    """Key poses ``[K, 22]`` (``nao.JOINTS`` order, rad) every 20 ms of one step, from the
    ready pose to the ready pose."""
    w = HIP_Y_M + WIDTH_M
    fp = foot_plan(genes, np.array([0.0, w]), np.array([0.0, -w]))
    z0 = -(HIP_Z_M + LEG_HEIGHT_M)
    feet = ((*fp.lead, fp.lead_is_left), (*fp.other, not fp.lead_is_left))
    torso = fp.torso

    def legs(torso_yaw: np.ndarray) -> dict[bool, np.ndarray]:
        out = {}
        for foot, yaw, lift, is_left in feet:
            rel = _rot(-torso_yaw, foot - torso)
            ankle = np.stack([rel[:, 0], rel[:, 1], z0 + lift], -1)
            out[is_left] = leg_ik(ankle, rot_z(yaw - torso_yaw), left=is_left)
        return out

    # the hip yaw-pitch is one motor, but a leg's IK value also depends on where its foot
    # is: the torso's yaw is corrected (secant steps) until both legs need the same value,
    # so the feet land where and as turned as planned
    y0, y1 = fp.yaw, fp.yaw + 1e-3
    f0 = _hyp_gap(legs(y0))
    for _ in range(6):
        f1 = _hyp_gap(legs(y1))
        slope = np.where(np.abs(f1 - f0) > 1e-12, (y1 - y0) / np.where(f1 == f0, 1, f1 - f0),
                         0.0)
        y0, f0, y1 = y1, f1, y1 - f1 * slope
    q = legs(y1)
    out = np.broadcast_to(nao.pose_vector(), (fp.t.size, len(nao.JOINTS))).copy()
    out[:, _L_COLS], out[:, _R_COLS] = q[True], q[False]
    out[:, nao.JOINTS.index("RHipYawPitch")] = out[:, nao.JOINTS.index("LHipYawPitch")]
    return np.clip(out, _LO, _HI)


def _hyp_gap(q: dict[bool, np.ndarray]) -> np.ndarray:
    return q[True][:, 0] - q[False][:, 0]


def ready_pose() -> np.ndarray:
    """The pose every step starts and ends in ``[22]``."""
    return poses(DEFAULT * np.r_[0, 0, 0, 1, 0, 1, 1, 1])[0]


def named(genes: np.ndarray) -> dict[str, float]:
    return {n: float(v) for n, v in zip(NAMES, np.asarray(genes, float), strict=True)}
