"""An omnidirectional NAO walk engine: a command ``(vx, vy, ω)`` -> joint targets by leg IK.

This is the reference the walk controller's phase tape is fitted to (:func:`fit_controller`,
then evolved closed loop, :mod:`.controller`); its structure is that of the walk engines NAO
teams run (B-Human's, ``/work/shared/reference/walking.md`` sections 1-2; Graf et al. 2009):
feet placed in Cartesian space relative to the torso, a fixed step period, the step size set by
the commanded velocity, the torso swayed from side to side, closed-form leg IK
(:mod:`evomotion.sim.robots.nao.leg_ik`).

Walk frame: the torso's, upright (metres, seconds, radians). Phase ``φ = t / T`` (cycles); the
left foot's phase is ``p = φ mod 1``, the right's ``(φ + 1/2) mod 1``. A foot swings during
the first ``w`` of its phase and stands the rest. Each foot's offset ``u(p) ∈ [-1/2, 1/2]``
goes from ``-1/2`` to ``+1/2`` on a cosine during the swing and back linearly during the
stance, so a stance foot moves back at ``d / ((1 - w) T)`` for a travel ``d``: the body moves
at the command when ``d = (vx, vy, ω) (1 - w) T``. Foot ``s`` (+1 left, -1 right):

    x = x_offset + u dx,      y = s (hip_y + width) + u dy + sway(φ),
    z = -(hip_z + leg_height) + lift(p) H,     yaw = s (u_s − u_{-s}) dψ / 2 (see below)

The NAO's two hip yaw-pitch joints are one motor, so the feet can only yaw in mirror image:
each foot gets half the relative yaw ``(u_left − u_right) dψ`` with its own sign, and its
``(x, y)`` is rotated about the torso by it. ``sway = -A cos(2π(φ − w/2) + ψ_s)`` shifts
both feet sideways: at ``ψ_s = 0``, at mid-swing towards the stance foot's side (the torso
towards the swing foot's): on the NAO's quick 0.48 s cycle the engine walks with it
(0.2 m/s commanded: 0.15 walked, nominal world), while the quasi-static phase ``ψ_s = π``,
the torso over the stance foot (what :mod:`.ik_gait` uses for other robots), stays up but
barely moves (0.2 m/s: 0.0 walked). ``lift = (1 − cos 2π p/w) / 2`` in swing.
Shoulder pitches swing against the legs, ``± arm vx cos(2π(φ − w/2))``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.joint_limits import JOINT_RANGES
from evomotion.sim.robots.nao.leg_ik import leg_ik, rot_y, rot_z

_LO, _HI = np.array([JOINT_RANGES[j] for j in nao.JOINTS]).T
_COL = {j: i for i, j in enumerate(nao.JOINTS)}


@dataclass(frozen=True)
class OmniGait:
    """The engine's settings (SI units); the defaults are a B-Human-like cautious gait."""

    period_s: float = 0.48  # one cycle = two steps
    swing_fraction: float = 0.45  # w
    step_height_m: float = 0.02  # H
    leg_height_m: float = 0.155  # hip joint to ankle, vertical
    width_m: float = 0.03  # extra lateral foot offset (each side)
    sway_m: float = 0.025  # A
    sway_phase_rad: float = 0.0  # ψ_s
    lean_rad: float = 0.05  # torso pitch forward
    x_offset_m: float = 0.0  # ankles forward of the torso origin
    arm_swing_rad_per_mps: float = 1.0  # shoulder pitch amplitude per m/s forward

    def travel(self, command: np.ndarray) -> np.ndarray:
        """``(dx, dy, dψ)[..., 3]``: each foot's travel per stance for ``command[..., 3]``."""
        return np.asarray(command, float) * (1.0 - self.swing_fraction) * self.period_s


def foot_offset(p: np.ndarray, w: float) -> tuple[np.ndarray, np.ndarray]:
    """``(u, lift)`` of a foot at its phase ``p ∈ [0, 1)`` (see the module doc)."""
    swing = p < w
    s = np.where(swing, p / w, 0.0)
    st = np.where(swing, 0.0, (p - w) / (1.0 - w))
    u = np.where(swing, -0.5 + 0.5 * (1.0 - np.cos(np.pi * s)), 0.5 - st)
    lift = np.where(swing, 0.5 * (1.0 - np.cos(2.0 * np.pi * s)), 0.0)
    return u, lift


def targets(gait: OmniGait, phase: np.ndarray, command: np.ndarray,
            foot_offsets: np.ndarray | None = None) -> np.ndarray:
    """Joint targets ``[T, 22]`` (``nao.JOINTS`` order, rad, clipped to the NAO's ranges) at
    ``phase[T]`` (cycles) for ``command[T, 3]`` (vx m/s, vy m/s, ω rad/s); ``foot_offsets[T,
    2, 2]`` (left, right; x, y; m) move the feet from where the engine puts them, added before
    each foot's turning yaw rotates it (the walk frame when not turning). A footstep
    adjustment: ``benchmarks/walk_capture_step.py`` places the swing foot by the capture
    point."""
    phi = np.asarray(phase, float)
    travel = gait.travel(command)
    dx, dy, dpsi = travel[..., 0], travel[..., 1], travel[..., 2]
    w = gait.swing_fraction
    u_l, lift_l = foot_offset(np.mod(phi, 1.0), w)
    u_r, lift_r = foot_offset(np.mod(phi + 0.5, 1.0), w)
    rel_yaw = (u_l - u_r) * dpsi
    sway = -gait.sway_m * np.cos(2 * np.pi * (phi - 0.5 * w) + gait.sway_phase_rad)
    out = np.broadcast_to(nao.pose_vector(), phi.shape + (len(nao.JOINTS),)).copy()
    lean = np.swapaxes(rot_y(np.full(phi.shape, gait.lean_rad)), -1, -2)  # walk -> torso
    off = (np.zeros(phi.shape + (2, 2)) if foot_offsets is None
           else np.asarray(foot_offsets, float))
    for f, (s, u, lift, leg) in enumerate(((1.0, u_l, lift_l, nao.LEFT_LEG),
                                           (-1.0, u_r, lift_r, nao.RIGHT_LEG))):
        yaw = s * 0.5 * rel_yaw
        x = gait.x_offset_m + u * dx + off[..., f, 0]
        y = s * (nao.HIP_OFFSET_Y_M + gait.width_m) + u * dy + sway + off[..., f, 1]
        c, sn = np.cos(yaw), np.sin(yaw)
        pos = np.stack([c * x - sn * y, sn * x + c * y,
                        -(nao.HIP_OFFSET_Z_M + gait.leg_height_m) + lift * gait.step_height_m],
                       axis=-1)
        ankle = (lean @ pos[..., None])[..., 0]
        out[..., [_COL[j] for j in leg]] = leg_ik(ankle, lean @ rot_z(yaw), left=s > 0)
    out[..., _COL["RHipYawPitch"]] = out[..., _COL["LHipYawPitch"]]  # one motor
    arm = gait.arm_swing_rad_per_mps * np.asarray(command, float)[..., 0] * np.cos(
        2 * np.pi * (phi - 0.5 * w))
    out[..., _COL["LShoulderPitch"]] += arm
    out[..., _COL["RShoulderPitch"]] -= arm
    return np.clip(out, _LO, _HI)
