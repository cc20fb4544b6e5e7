"""Kick motion: genome -> kicking-foot Cartesian trajectory -> joint targets (seed 3.2.2-3.3).

The right foot kicks, the left foot supports; the torso stays upright (seed: torso pitch within
3 degrees). Phases after ``settle_s`` of standing (all lengths m, angles rad, times s, ankle
positions in the torso frame, starting from the Webots crouch of :mod:`evomotion.sim.nao`):

0. weight shift (``t_shift_s``): both ankles move by ``-shift_y_m`` in y (torso over the left
   foot), smoothstep ``3u^2 - 2u^3``;
1. lift (``t_lift_s``): the right ankle goes from rest to ``L = rest + (lift_x, kick_y, lift_z)``;
2. kick (``t_kick_s``): ``L -> K = rest + (kick_x, kick_y, kick_z)``, time warp ``u^kick_ease``
   (the foot accelerates through the ball);
3. retract (``t_retract_s``): ``K -> rest`` (set down), then the weight shifts back (``t_shift_s``).

Each phase is a cubic Bézier (seed eq. 13) ``P0, P0 + c/3 + b n, P0 + 2c/3 + b n, P3`` with
chord ``c = P3 - P0``, ``n`` the upward normal of the chord in the x-z plane and ``b`` the
phase's bulge gene; lift and retract use the smoothstep in time. Foot pitch is interpolated
``0 -> lift_pitch -> kick_pitch -> 0``. Both legs go through :func:`leg_ik` with hip yaw-pitch 0
(feet without yaw), vectorised over individuals and time steps.
"""

from __future__ import annotations

import numpy as np

from evomotion.sim import nao
from evomotion.sim.nao.leg_ik import leg_fk, leg_ik, rot_y

#: (name, lower, upper) of the 15 genes.
GENES: tuple[tuple[str, float, float], ...] = (
    ("shift_y_m", 0.02, 0.07), ("t_shift_s", 0.3, 1.2),
    ("lift_x_m", -0.10, 0.02), ("lift_z_m", 0.02, 0.09), ("lift_pitch", -0.5, 0.5),
    ("t_lift_s", 0.15, 0.6), ("lift_bulge_m", -0.03, 0.03),
    ("kick_x_m", 0.04, 0.18), ("kick_z_m", 0.01, 0.07), ("kick_pitch", -0.5, 0.5),
    ("t_kick_s", 0.06, 0.4), ("kick_bulge_m", -0.04, 0.04), ("kick_ease", 1.0, 3.0),
    ("kick_y_m", -0.03, 0.04), ("t_retract_s", 0.2, 0.8),
)
GENE_INDEX = {name: i for i, (name, _, _) in enumerate(GENES)}
SETTLE_S = 0.3

LEFT, RIGHT = nao.LEFT_LEG, nao.RIGHT_LEG


def rest_pose() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Initial 22 targets and the left/right ankle positions (torso frame) of the crouch."""
    q = nao.pose_vector()
    idx = nao.joint_columns(LEFT), nao.joint_columns(RIGHT)
    return q, leg_fk(q[idx[0]], True)[0], leg_fk(q[idx[1]], False)[0]


def gene(genomes: np.ndarray, name: str) -> np.ndarray:
    return genomes[:, GENE_INDEX[name]]


def execution_time_s(genomes: np.ndarray) -> np.ndarray:
    """Time from the start of the weight shift to the end of the shift back (s)."""
    g = np.atleast_2d(genomes)
    return (2 * gene(g, "t_shift_s") + gene(g, "t_lift_s") + gene(g, "t_kick_s")
            + gene(g, "t_retract_s"))


def _smooth(u: np.ndarray) -> np.ndarray:
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3 - 2 * u)


def _bezier_phase(p0: np.ndarray, p3: np.ndarray, bulge: np.ndarray,
                  tau: np.ndarray) -> np.ndarray:
    """Points ``[B, T, 3]`` of the phase curve at parameters ``tau[B, T]``."""
    c = p3 - p0  # [B, 3]
    n = np.stack([-c[:, 2], np.zeros(len(c)), c[:, 0]], axis=1)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-9)
    n *= np.where(n[:, 2:3] < 0, -1.0, 1.0)  # upward normal
    p1 = p0 + c / 3 + bulge[:, None] * n
    p2 = p0 + 2 * c / 3 + bulge[:, None] * n
    t = tau[..., None]
    P = [p[:, None, :] for p in (p0, p1, p2, p3)]
    return ((1 - t) ** 3 * P[0] + 3 * (1 - t) ** 2 * t * P[1] + 3 * (1 - t) * t**2 * P[2]
            + t**3 * P[3])


def foot_trajectories(genomes: np.ndarray, times_s: np.ndarray) -> dict[str, np.ndarray]:
    """Ankle targets ``left``, ``right`` ``[B, T, 3]`` and right-foot ``pitch`` ``[B, T]``."""
    g = np.atleast_2d(genomes)
    _, l0, r0 = rest_pose()
    t = times_s[None, :] - SETTLE_S
    ts, tl, tk, tr = (gene(g, k)[:, None] for k in ("t_shift_s", "t_lift_s", "t_kick_s",
                                                     "t_retract_s"))
    e1, e2, e3 = ts + tl, ts + tl + tk, ts + tl + tk + tr
    shift = _smooth(t / ts) - _smooth((t - e3) / ts)
    dy = -gene(g, "shift_y_m")[:, None] * shift
    left = np.broadcast_to(l0, (len(g), t.shape[1], 3)).copy()
    left[..., 1] += dy
    rest = np.broadcast_to(r0, (len(g), 3)).copy()
    rest[:, 1] -= gene(g, "shift_y_m")
    L = rest + np.stack([gene(g, "lift_x_m"), gene(g, "kick_y_m"), gene(g, "lift_z_m")], 1)
    K = rest + np.stack([gene(g, "kick_x_m"), gene(g, "kick_y_m"), gene(g, "kick_z_m")], 1)
    lift = _bezier_phase(rest, L, gene(g, "lift_bulge_m"), _smooth((t - ts) / tl))
    u_k = np.clip((t - e1) / tk, 0.0, 1.0) ** gene(g, "kick_ease")[:, None]
    kick = _bezier_phase(L, K, gene(g, "kick_bulge_m"), u_k)
    back = _bezier_phase(K, rest, np.zeros(len(g)), _smooth((t - e2) / tr))
    right = np.broadcast_to(r0, (len(g), t.shape[1], 3)).copy()
    right[..., 1] += dy
    for lo, hi, curve in ((ts, e1, lift), (e1, e2, kick), (e2, e3, back)):
        m = (t >= lo) & (t < hi)
        right[m] = curve[m]
    lp, kp = gene(g, "lift_pitch")[:, None], gene(g, "kick_pitch")[:, None]
    pitch = np.where(t < e1, lp * _smooth((t - ts) / tl),
                     np.where(t < e2, lp + (kp - lp) * np.clip((t - e1) / tk, 0, 1),
                              kp * (1 - _smooth((t - e2) / tr))))
    return {"left": left, "right": right, "pitch": pitch}


def joint_targets(genomes: np.ndarray, times_s: np.ndarray) -> np.ndarray:
    """Actuator targets ``[B, T, 22]`` (order :data:`evomotion.sim.nao.JOINTS`)."""
    g = np.atleast_2d(genomes)
    q_rest, _, _ = rest_pose()
    feet = foot_trajectories(g, times_s)
    ql = leg_ik(feet["left"], np.eye(3), left=True)
    qr = leg_ik(feet["right"], rot_y(feet["pitch"]), left=False)
    ctrl = np.broadcast_to(q_rest, (len(g), len(times_s), len(q_rest))).copy()
    ctrl[..., nao.joint_columns(LEFT)] = ql
    ctrl[..., nao.joint_columns(RIGHT)] = qr
    ctrl[..., nao.JOINTS.index("RHipYawPitch")] = 0.0  # shared motor, feet have no yaw
    ctrl[..., nao.JOINTS.index("LHipYawPitch")] = 0.0
    return ctrl
