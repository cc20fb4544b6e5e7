"""Joint-target trajectories for a paper-003 plan (quasi-static; SI units, one row per step).

A plan is a list of states ``{"body": [x, y, phi], "feet": [[x, y] x 4], ...}`` in paper
units, feet in world coordinates (the ``states`` of ``plan.json``). Each transition becomes
segments: first every foot that moved swings, one at a time in leg order, with the body at
its old pose (normally exactly one foot, or none); then, if the body pose changed, the body
moves with all four feet fixed in the world (normally a pure rotation about the centre or a
translation along body Y; any change of (x, y, phi) is interpolated linearly).

- Body segment: ``(x, y, phi)`` follows a smoothstep (3u^2 - 2u^3, zero speed at both
  ends) over ``max(distance / metres_per_second, |dphi| / radians_per_second,
  MIN_BODY_SECONDS)``; the feet's torso-frame positions come from the planned pose and IK.
- Swing segment (``leg_seconds``, body fixed): the foot moves in the hip's polar coordinates
  (length and angle, so it stays in the annular sector) while its height rises to ``lift_m``
  over the first ``RISE`` of the time, holds, and falls back over the last ``RISE``; the
  horizontal motion runs between ``HOLD`` and ``1 - HOLD``.

The torso is commanded at ``body_height_m`` with zero roll and pitch; nothing closes a loop
on the simulated torso (open-loop servo targets).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from evomotion.core.angles import wrap_angle as wrap
from evomotion.sim.quadruped.ik import legs_ik
from evomotion.sim.quadruped.model import QuadrupedSpec

MIN_BODY_SECONDS = 0.2
RISE = 0.3  # fraction of a swing spent lifting (and lowering) the foot
HOLD = 0.15  # fraction of a swing before the horizontal motion starts (and after it ends)
POSE_TOL = 1e-9  # [paper units, rad]: smaller changes are no motion


@dataclass
class Timeline:
    """Per physics step: joint targets ``q[T, 12]``, planned body pose ``body[T, 3]``
    (m, m, rad), transition index ``transition[T]`` (-1: the initial settle, ``n - 1``: the
    final hold) and whether a foot is swinging ``swing[T]``; ``segments`` lists
    ``(kind, transition, leg)`` per segment, ``kind`` in ``"body", "leg"``."""

    q: np.ndarray
    body: np.ndarray
    transition: np.ndarray
    swing: np.ndarray
    segments: list[tuple[str, int, int]] = field(default_factory=list)


def smoothstep(u: np.ndarray) -> np.ndarray:
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def plan_arrays(states: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """``(body[n, 3], feet[n, 4, 2])`` of plan states, in paper units (NaN kept)."""
    body = np.array([s["body"] for s in states], dtype=float).reshape(len(states), 3)
    feet = np.array([s["feet"] for s in states], dtype=float).reshape(len(states), 4, 2)
    return body, feet


def _torso_feet(spec: QuadrupedSpec, pose: np.ndarray, feet_w: np.ndarray) -> np.ndarray:
    """Foot centres ``[T, 4, 3]`` [m] in the torso frame for poses ``[T, 3]`` (m, m, rad)
    and world feet ``[T, 4, 2]`` or ``[4, 2]`` [m]."""
    c, s = np.cos(pose[:, 2])[:, None], np.sin(pose[:, 2])[:, None]
    dx = feet_w[..., 0] - pose[:, None, 0]
    dy = feet_w[..., 1] - pose[:, None, 1]
    z = np.full(dx.shape, -spec.foot_drop_m)
    return np.stack([c * dx + s * dy, -s * dx + c * dy, z], axis=-1)


def _steps(seconds: float, dt: float) -> int:
    return max(1, int(math.ceil(seconds / dt - 1e-9)))


def _hold(spec: QuadrupedSpec, pose: np.ndarray, feet_w: np.ndarray, n: int) -> np.ndarray:
    return np.repeat(legs_ik(spec, _torso_feet(spec, pose[None], feet_w))[:1], n, axis=0)


def _body_segment(spec: QuadrupedSpec, p0: np.ndarray, p1: np.ndarray, feet_w: np.ndarray,
                  mps: float, rps: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    dp = p1 - p0
    dp[2] = wrap(dp[2])
    secs = max(float(np.hypot(dp[0], dp[1])) / mps, abs(float(dp[2])) / rps, MIN_BODY_SECONDS)
    n = _steps(secs, dt)
    u = smoothstep(np.arange(1, n + 1) / n)
    pose = p0 + u[:, None] * dp
    return legs_ik(spec, _torso_feet(spec, pose, feet_w)), pose


def _swing_segment(spec: QuadrupedSpec, pose: np.ndarray, feet_w: np.ndarray, leg: int,
                   target_w: np.ndarray, seconds: float, lift_m: float, dt: float
                   ) -> np.ndarray:
    n = _steps(seconds, dt)
    u = np.arange(1, n + 1) / n
    ends = _torso_feet(spec, pose[None], np.stack([feet_w[leg], target_w])[None])[0]
    hip = spec.hips_m()[leg]
    rel = ends[:, :2] - hip[:2]
    length = np.hypot(rel[:, 0], rel[:, 1])
    ang = np.arctan2(rel[:, 1], rel[:, 0])
    d_ang = wrap(ang[1] - ang[0])
    s = smoothstep((u - HOLD) / (1.0 - 2.0 * HOLD))
    height = lift_m * np.minimum(smoothstep(u / RISE), smoothstep((1.0 - u) / RISE))
    a = ang[0] + s * d_ang
    rr = length[0] + s * (length[1] - length[0])
    feet = np.repeat(_torso_feet(spec, pose[None], feet_w), n, axis=0)
    feet[:, leg] = np.stack([hip[0] + rr * np.cos(a), hip[1] + rr * np.sin(a),
                             height - spec.foot_drop_m], axis=-1)
    return legs_ik(spec, feet)


def build_timeline(spec: QuadrupedSpec, states: list[dict], *, leg_seconds: float,
                   metres_per_second: float, radians_per_second: float, lift_m: float,
                   settle_seconds: float, final_seconds: float) -> Timeline:
    """Joint targets for ``states`` (see the module docstring) at ``spec.timestep``."""
    dt, unit = spec.timestep, spec.unit_m
    body, feet = plan_arrays(states)
    body_m = body * [unit, unit, 1.0]
    feet_m = feet * unit
    qs, poses, trans, swing, segs = [], [], [], [], []

    def add(q: np.ndarray, pose: np.ndarray, t: int, swinging: bool) -> None:
        qs.append(q)
        poses.append(np.broadcast_to(pose, (len(q), 3)))
        trans.append(np.full(len(q), t))
        swing.append(np.full(len(q), swinging))

    pose, cur = body_m[0].copy(), feet_m[0].copy()
    add(_hold(spec, pose, cur, _steps(settle_seconds, dt)), pose, -1, False)
    for t in range(len(states) - 1):
        for leg in range(4):
            if np.max(np.abs(feet[t + 1, leg] - cur[leg] / unit)) > POSE_TOL:
                add(_swing_segment(spec, pose, cur, leg, feet_m[t + 1, leg], leg_seconds,
                                   lift_m, dt), pose, t, True)
                cur[leg] = feet_m[t + 1, leg]
                segs.append(("leg", t, leg))
        change = body_m[t + 1] - pose
        change[2] = wrap(change[2])
        if np.max(np.abs(change / [unit, unit, 1.0])) > POSE_TOL:
            q, path = _body_segment(spec, pose, pose + change, cur, metres_per_second,
                                    radians_per_second, dt)
            add(q, path, t, False)
            pose = pose + change
            segs.append(("body", t, -1))
    add(_hold(spec, pose, cur, _steps(final_seconds, dt)), pose, len(states) - 1, False)
    return Timeline(np.concatenate(qs), np.concatenate(poses), np.concatenate(trans),
                    np.concatenate(swing), segs)


def plan_seconds(spec: QuadrupedSpec, states: list[dict], *, leg_seconds: float,
                 metres_per_second: float, radians_per_second: float, settle_seconds: float,
                 final_seconds: float) -> float:
    """Simulated seconds :func:`build_timeline` would take for ``states`` (computed from the
    plan's numbers alone, before anything of that length is allocated); inf if a state is
    not finite."""
    body, feet = plan_arrays(states)
    if not (np.isfinite(body).all() and np.isfinite(feet).all()):
        return math.inf
    dt = spec.timestep
    legs = int(np.count_nonzero(np.abs(np.diff(feet, axis=0)).max(axis=-1) > POSE_TOL))
    d = np.diff(body, axis=0)
    turn = np.abs(wrap(d[:, 2]))
    dist = np.hypot(d[:, 0], d[:, 1]) * spec.unit_m
    moved = np.maximum(np.abs(d[:, :2]).max(axis=1), turn) > POSE_TOL
    secs = np.maximum(np.maximum(dist / metres_per_second, turn / radians_per_second),
                      MIN_BODY_SECONDS)
    steps = legs * _steps(leg_seconds, dt) + float(np.sum(np.ceil(secs[moved] / dt)))
    return (steps + _steps(settle_seconds, dt) + _steps(final_seconds, dt)) * dt


def initial_qpos(spec: QuadrupedSpec, states: list[dict], nq: int) -> np.ndarray:
    """``qpos`` of the first state: torso at the planned pose and ``body_height_m``, joints
    from IK (feet on the floor)."""
    body, feet = plan_arrays(states[:1])
    pose = body[0] * [spec.unit_m, spec.unit_m, 1.0]
    qpos = np.zeros(nq)
    qpos[:3] = pose[0], pose[1], spec.body_height_m
    qpos[3:7] = math.cos(pose[2] / 2), 0.0, 0.0, math.sin(pose[2] / 2)
    qpos[7:19] = _hold(spec, pose, feet[0] * spec.unit_m, 1)[0]
    return qpos

