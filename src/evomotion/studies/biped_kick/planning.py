"""Kick-point choice and approach path (paper 002, sections 3.1 and 3.2.1).

Geometry (field frame, metres, radians; robot pose ``(x, y, theta)``, ball ``b``, goal ``g``).
The paper's formulas were lost in extraction; this is our reconstruction from its text and Fig. 4:

* The ball is inflated to a circle of radius ``R`` (so the robot does not touch it on the way).
  Candidate kick points ``K_j = b - R (cos phi_j, sin phi_j)`` lie on the arc within
  ``max_offset`` of the ideal point ``b - R u_g`` behind the ball (``u_g`` = ball->goal unit
  vector); from ``K_j`` the robot kicks towards the ball, heading ``psi_K = phi_j``.
* ``C_turn``: the turning the robot needs, ``|wrap(psi_d - theta)| + |wrap(psi_K - psi_d)|``
  with ``psi_d`` the direction of the walking vector ``d = K - robot`` (the paper's angles
  alpha (heading vs. robot->ball vector r) and beta (d vs. r) combine into these two turns),
  plus ``|wrap(psi_K - psi_goal)|``, the aiming error of a kick from ``K_j``.
* ``C_dist = |d|``.  ``C_kick = w_t C_turn + w_d C_dist``; the best kick point minimises it.

Approach path: the cubic Bézier ``B(t) = sum_k binom(3,k) (1-t)^(3-k) t^k P_k`` (the paper's eq. 13)
with ``P0`` the robot, ``P1 = P0 + a h`` on the robot's heading ``h``, ``P2 = K - a u_K`` on the
kick line (ball->goal line through the ball, extended behind the kick point) and ``P3 = K``;
``a = |d| / 3`` by default. The robot arrives facing the kick direction.

Walking-speed model (stated, NAO-like, used for both paths): forward speed ``v = 0.20 m/s``,
turning rate ``omega = 0.6 rad/s`` (in place or while walking); on a curve with curvature
``kappa`` the speed is ``min(v, omega / |kappa|)``. Baseline "turn, walk straight, align":
turn in place to ``psi_d``, walk ``|d|`` straight, turn in place to ``psi_K``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from evomotion.core.angles import wrap_angle_upper as wrap


@dataclass(frozen=True)
class WalkModel:
    speed_m_s: float = 0.20
    turn_rad_s: float = 0.6


@dataclass(frozen=True)
class KickPlan:
    candidates: np.ndarray  # [n, 2] kick points on the inflated circle
    cost: np.ndarray  # [n] C_kick
    best: int
    kick_point: np.ndarray  # [2]
    kick_heading: float  # rad
    control_points: np.ndarray  # [4, 2] Bézier P0..P3


def kick_costs(robot: np.ndarray, ball: np.ndarray, goal: np.ndarray, radius_m: float = 0.2,
               n: int = 36, max_offset: float = np.pi / 3, w_turn: float = 1.0,
               w_dist: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Candidates ``[n, 2]``, their headings, ``C_turn`` and ``C_dist`` (vectorised)."""
    robot, ball, goal = (np.asarray(v, dtype=float) for v in (robot, ball, goal))
    psi_goal = np.arctan2(*(goal - ball)[::-1])
    phi = psi_goal + np.linspace(-max_offset, max_offset, n)
    K = ball - radius_m * np.stack([np.cos(phi), np.sin(phi)], axis=1)
    d = K - robot[:2]
    psi_d = np.arctan2(d[:, 1], d[:, 0])
    c_turn = (np.abs(wrap(psi_d - robot[2])) + np.abs(wrap(phi - psi_d))
              + np.abs(wrap(phi - psi_goal)))
    return K, phi, c_turn, np.linalg.norm(d, axis=1)


def plan_kick(robot: np.ndarray, ball: np.ndarray, goal: np.ndarray, radius_m: float = 0.2,
              n: int = 36, w_turn: float = 1.0, w_dist: float = 1.0,
              handle: float | None = None) -> KickPlan:
    """Best kick point (min ``C_kick``) and the Bézier control points of the approach."""
    K, phi, c_turn, c_dist = kick_costs(robot, ball, goal, radius_m, n)
    cost = w_turn * c_turn + w_dist * c_dist
    j = int(np.argmin(cost))
    p0 = np.asarray(robot[:2], dtype=float)
    a = c_dist[j] / 3 if handle is None else handle
    h = np.array([np.cos(robot[2]), np.sin(robot[2])])
    u_k = np.array([np.cos(phi[j]), np.sin(phi[j])])
    ctrl = np.stack([p0, p0 + a * h, K[j] - a * u_k, K[j]])
    return KickPlan(K, cost, j, K[j], float(phi[j]), ctrl)


def bezier(ctrl: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Cubic Bézier points ``[len(t), dim]`` (the paper's eq. 13)."""
    t = np.asarray(t, dtype=float)[:, None]
    c = np.asarray(ctrl, dtype=float)
    return ((1 - t) ** 3 * c[0] + 3 * (1 - t) ** 2 * t * c[1] + 3 * (1 - t) * t**2 * c[2]
            + t**3 * c[3])


def bezier_time(ctrl: np.ndarray, walk: WalkModel = WalkModel(),
                samples: int = 400) -> tuple[float, float]:
    """Length (m) and walking time (s) of the Bézier path under ``walk``."""
    t = np.linspace(0.0, 1.0, samples + 1)
    c = np.asarray(ctrl, dtype=float)
    d1 = 3 * ((1 - t[:, None]) ** 2 * (c[1] - c[0]) + 2 * (1 - t[:, None]) * t[:, None]
              * (c[2] - c[1]) + t[:, None] ** 2 * (c[3] - c[2]))
    d2 = 6 * ((1 - t[:, None]) * (c[2] - 2 * c[1] + c[0]) + t[:, None] * (c[3] - 2 * c[2]
                                                                           + c[1]))
    speed = np.linalg.norm(d1, axis=1)
    kappa = np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / np.maximum(speed, 1e-12) ** 3
    v = np.minimum(walk.speed_m_s, walk.turn_rad_s / np.maximum(kappa, 1e-12))
    ds = speed * (t[1] - t[0])
    ds_mid = 0.5 * (ds[1:] + ds[:-1])
    v_mid = 0.5 * (v[1:] + v[:-1])
    return float(ds_mid.sum()), float((ds_mid / v_mid).sum())


def baseline_time(robot: np.ndarray, plan: KickPlan,
                  walk: WalkModel = WalkModel()) -> tuple[float, float]:
    """Length (m) and time (s) of "turn in place, walk straight, align in place"."""
    d = plan.kick_point - np.asarray(robot[:2], dtype=float)
    psi_d = np.arctan2(d[1], d[0])
    turns = abs(float(wrap(psi_d - robot[2]))) + abs(float(wrap(plan.kick_heading - psi_d)))
    dist = float(np.linalg.norm(d))
    return dist, dist / walk.speed_m_s + turns / walk.turn_rad_s


@dataclass(frozen=True)
class AimedPlan:
    """The stand pose for an aimed kick and the Bézier approach to it."""

    aims_rad: np.ndarray  # [n] candidate aims (kick direction - robot heading)
    stand: np.ndarray  # [n, 3] stand pose (x, y, heading) for each aim
    cost: np.ndarray  # [n] C_kick
    best: int
    control_points: np.ndarray  # [4, 2] Bézier P0..P3 of the approach to stand[best]

    @property
    def aim_rad(self) -> float:
        return float(self.aims_rad[self.best])

    @property
    def pose(self) -> np.ndarray:
        return self.stand[self.best]


def plan_aimed_kick(robot: np.ndarray, ball: np.ndarray, target: np.ndarray,
                    ball_local: Callable[[np.ndarray], np.ndarray], max_aim_rad: float,
                    n: int = 61, w_turn: float = 1.0, w_dist: float = 1.0,
                    w_aim: float = 0.5) -> AimedPlan:
    """Where to stand for an aimed kick (the paper's kick-point choice with the kick's aim as
    the free variable): for aim ``a`` the robot faces ``psi = psi_T - a`` (``psi_T`` the
    ball->target direction) and stands so that the ball lies at ``ball_local(a)`` (``[n, 2]``,
    robot frame: x forward, y left). ``C_turn = |wrap(psi_d - theta)| + |wrap(psi - psi_d)|
    + w_aim |a|`` (the aimed kick is less accurate than the straight one), ``C_dist = |d|``,
    ``C_kick = w_turn C_turn + w_dist C_dist``; approach as :func:`plan_kick`."""
    robot, ball, target = (np.asarray(v, dtype=float) for v in (robot, ball, target))
    psi_t = float(np.arctan2(*(target - ball)[::-1]))
    aims = np.linspace(-max_aim_rad, max_aim_rad, n)
    psi = psi_t - aims
    loc = np.asarray(ball_local(aims), dtype=float).reshape(n, 2)
    c, s = np.cos(psi), np.sin(psi)
    stand_xy = ball - np.stack([c * loc[:, 0] - s * loc[:, 1], s * loc[:, 0] + c * loc[:, 1]],
                               axis=1)
    d = stand_xy - robot[:2]
    dist = np.linalg.norm(d, axis=1)
    psi_d = np.where(dist > 1e-9, np.arctan2(d[:, 1], d[:, 0]), robot[2])
    c_turn = (np.abs(wrap(psi_d - robot[2])) + np.abs(wrap(psi - psi_d)) + w_aim * np.abs(aims))
    cost = w_turn * c_turn + w_dist * dist
    j = int(np.argmin(cost))
    p0 = robot[:2]
    a = dist[j] / 3
    h = np.array([np.cos(robot[2]), np.sin(robot[2])])
    u = np.array([np.cos(psi[j]), np.sin(psi[j])])
    ctrl = np.stack([p0, p0 + a * h, stand_xy[j] - a * u, stand_xy[j]])
    return AimedPlan(aims, np.column_stack([stand_xy, psi]), cost, j, ctrl)
