"""A parameterised open-loop NAO walk: 14 interpretable genes -> joint targets (22 servos).

Why this parameterisation: it is the one RoboCup teams tune, with CMA-ES, on their walk
engines (UT Austin Villa optimised the parameters of its walk engine with CMA-ES in the 3D
simulation league, AAAI 2012; B-Human's walk is configured by step length, height, period and
lean, ``/work/shared/reference/walking.md`` sections 1-2). Every gene has a physical meaning
and a bound taken from the robot, and *every* genome decodes to a kinematically valid gait
(foot positions in Cartesian space through the closed-form leg IK of
:mod:`evomotion.sim.robots.nao.leg_ik`), so the search spends no evaluations on joint-space
noise, and
14 genes suit CMA-ES (lambda ~ 12-24). Open loop (no IMU feedback): what is evaluated is
exactly a keyframe motion, so the exported Webots ``.motion`` replays the same gait.

Gait (walk frame: upright, yaw of the torso, origin at the torso origin; metres, seconds):
phase ``phi = (t - ready_s) / T``; the left foot's phase is ``phi mod 1``, the right's
``(phi + 1/2) mod 1``. A foot swings during the first ``w`` (``swing_fraction``) of its phase,
forward from ``-L_s/2`` to ``+L_s/2`` on a cosine profile, lifted by
``H (1 - cos 2 pi s) / 2``; in stance it moves back linearly, so the body advances at
``v = L / ((1 - w) T)``. Both feet sway laterally by ``A cos(2 pi (phi - w/2) + psi)`` (the
torso moves over the stance foot), stand ``0.050 + width`` from the midline and
``0.085 + h`` below the torso origin, ``x_offset`` forward. ``L_s = L (1 + s trim)``
(s = +1 left, -1 right) steers. The torso leans by ``lean``: ankle targets and the flat foot
orientation are expressed in the torso frame rotated by ``lean`` about y; the swing foot pitches
by ``foot_pitch sin(pi s)``. Arms swing against the legs (``ShoulderPitch +- arm cos``).

:data:`DEFAULT`, where CMA-ES starts, is a hand-set cautious gait in the style of B-Human's
configuration (a 0.56 s cycle, i.e. 280 ms per step; 2 cm foot lift; knees bent to a 0.155 m
hip-to-ankle height; feet 3 cm wider than the hips; no lean): it walks about 0.17 m/s and
stays up in the 8 training worlds of seed 0, so the search starts from a walk, not a shuffle.

Start-up, cycle, stop: 0.6 s from the initial crouch to the ready pose (joint space,
smoothstep), ``RAMP_CYCLES`` cycles with the amplitudes rising from 0 to 1, the steady cycles,
``RAMP_CYCLES`` cycles falling back to 0, then the ready pose is held. The period is rounded
to a multiple of 40 ms, so every cycle is a whole number of 20 ms key poses and the Webots
motion is exactly a start, a repeated cycle and a stop.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.joint_limits import JOINT_RANGES
from evomotion.sim.robots.nao.leg_ik import leg_ik, rot_x, rot_y

#: (name, low, high, default) of each gene; SI units (m, s, rad)
GENES: tuple[tuple[str, float, float, float], ...] = (
    ("period_s", 0.32, 0.64, 0.56),  # one cycle = two steps
    ("step_length_m", 0.0, 0.12, 0.08),  # L: each foot's travel relative to the torso
    ("step_height_m", 0.005, 0.04, 0.02),  # H: swing foot lift
    ("leg_height_m", 0.140, 0.195, 0.155),  # h: hip joint to ankle, vertical
    ("sway_m", 0.0, 0.05, 0.03),  # A: lateral sway amplitude of the torso over the feet
    ("sway_phase_rad", -0.8, 0.8, 0.0),  # psi: sway lead (+) or lag (-) on the steps
    ("lean_rad", -0.05, 0.30, 0.0),  # torso pitch forward
    ("width_m", -0.01, 0.05, 0.03),  # extra lateral foot offset (each side)
    ("swing_fraction", 0.30, 0.50, 0.45),  # w: share of a cycle a foot is in the air
    ("arm_swing_rad", 0.0, 0.6, 0.2),  # shoulder pitch amplitude
    ("x_offset_m", -0.03, 0.03, 0.0),  # ankles forward of the torso origin
    ("turn_trim", -0.2, 0.2, 0.0),  # step length asymmetry (left +, right -)
    ("foot_pitch_rad", -0.2, 0.2, 0.0),  # swing foot pitch (toe up +) at mid swing
    ("lift_roll_rad", -0.1, 0.1, 0.0),  # swing foot roll (outward +) at mid swing
)
NAMES: tuple[str, ...] = tuple(g[0] for g in GENES)
LOWER = np.array([g[1] for g in GENES])
UPPER = np.array([g[2] for g in GENES])
DEFAULT = np.array([g[3] for g in GENES])
INDEX = {name: i for i, name in enumerate(NAMES)}

POSE_MS = 20  # key poses every 20 ms (the .motion and the evaluation use the same ones)
PERIOD_QUANTUM_MS = 2 * POSE_MS  # a cycle is a whole number of pose pairs
READY_S = 0.6  # initial crouch -> ready pose
RAMP_CYCLES = 2  # cycles of rising (and of falling) amplitude
HIP_Z_M = nao.HIP_OFFSET_Z_M
HIP_Y_M = nao.HIP_OFFSET_Y_M
#: the real NAO's joint ranges (rad) in ``nao.JOINTS`` order: every target is clipped to them
_RANGE_LO, _RANGE_HI = np.array([JOINT_RANGES[j] for j in nao.JOINTS]).T


@dataclass(frozen=True)
class Schedule:
    """Times of one decoded walk (ms on the 20 ms pose grid)."""

    period_ms: int
    ready_ms: int
    ramp_ms: int  # each ramp
    steady_ms: int
    hold_ms: int

    @property
    def walk_end_ms(self) -> int:
        """End of the stop ramp (the ready pose is held from here)."""
        return self.ready_ms + 2 * self.ramp_ms + self.steady_ms

    @property
    def total_ms(self) -> int:
        return self.walk_end_ms + self.hold_ms


def period_ms(period_s: np.ndarray | float) -> np.ndarray:
    """The period gene rounded to a multiple of 40 ms (ms, integer)."""
    q = PERIOD_QUANTUM_MS
    return (np.maximum(np.rint(np.asarray(period_s) * 1000.0 / q), 1) * q).astype(np.int64)


def schedule(period_s: float, walk_s: float, hold_s: float) -> Schedule:
    """Start-up, ramps, ``ceil(walk_s / T)`` steady cycles and the hold for one period."""
    p = int(period_ms(period_s))
    steady = int(math.ceil(walk_s * 1000.0 / p - 1e-9)) * p
    return Schedule(p, int(round(READY_S * 1000)), RAMP_CYCLES * p, steady,
                    int(round(hold_s * 1000 / POSE_MS)) * POSE_MS)


def _smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def envelope(t_ms: np.ndarray, s: Schedule) -> np.ndarray:
    """Amplitude in [0, 1] at ``t_ms``: 0 before the walk, smooth ramps, 1 when steady."""
    a = s.ready_ms
    up = _smoothstep((t_ms - a) / s.ramp_ms)
    down = _smoothstep((s.walk_end_ms - t_ms) / s.ramp_ms)
    return np.minimum(up, down)


def _foot(p: np.ndarray, L: np.ndarray, H: np.ndarray, w: np.ndarray,
          pitch: np.ndarray, roll: np.ndarray) -> tuple[np.ndarray, ...]:
    """(x, lift, pitch, roll) of a foot at its phase ``p`` in [0, 1)."""
    swing = p < w
    s = np.where(swing, p / w, 0.0)
    st = np.where(swing, 0.0, (p - w) / (1.0 - w))
    x = np.where(swing, -0.5 * L + L * 0.5 * (1.0 - np.cos(np.pi * s)), 0.5 * L - L * st)
    lift = np.where(swing, 0.5 * (1.0 - np.cos(2.0 * np.pi * s)), 0.0)
    bump = np.where(swing, np.sin(np.pi * s), 0.0)
    return x, lift * H, bump * pitch, bump * roll


def _gait(g: np.ndarray, t_ms: np.ndarray, s: Schedule) -> np.ndarray:
    """Unclipped walk targets ``[P, K, 22]`` (no start-up blend)."""
    col = {n: g[:, i, None] for n, i in INDEX.items()}  # [P, 1] each
    t = np.asarray(t_ms, dtype=float)[None, :]
    e = envelope(t, s)
    phi = (t - s.ready_ms) / float(s.period_ms)
    out = np.broadcast_to(nao.pose_vector(), (g.shape[0], t.shape[1], len(nao.JOINTS))).copy()
    shape = (g.shape[0], t.shape[1])
    e = np.broadcast_to(e, shape)
    Rl = np.swapaxes(rot_y(np.broadcast_to(col["lean_rad"], shape)), -1, -2)  # walk->torso
    sway = e * col["sway_m"] * np.cos(2 * np.pi * (phi - 0.5 * col["swing_fraction"])
                                      + col["sway_phase_rad"])
    for side, leg in ((1.0, nao.LEFT_LEG), (-1.0, nao.RIGHT_LEG)):
        p = np.mod(phi + (0.0 if side > 0 else 0.5), 1.0)
        L = col["step_length_m"] * (1.0 + side * col["turn_trim"])
        x, z, fp, fr = _foot(p, L, col["step_height_m"], col["swing_fraction"],
                             col["foot_pitch_rad"], col["lift_roll_rad"])
        pos = np.stack(np.broadcast_arrays(
            col["x_offset_m"] + e * x,
            side * (HIP_Y_M + col["width_m"]) + sway,
            -(HIP_Z_M + col["leg_height_m"]) + e * z), axis=-1)  # [P, K, 3] walk frame
        ankle = (Rl @ pos[..., None])[..., 0]
        foot_R = Rl @ rot_y(e * fp) @ rot_x(side * e * fr)
        out[..., [nao.JOINTS.index(j) for j in leg]] = leg_ik(ankle, foot_R, left=side > 0)
    arm = e * col["arm_swing_rad"] * np.cos(2 * np.pi * (phi - 0.5 * col["swing_fraction"]))
    out[..., nao.JOINTS.index("LShoulderPitch")] += arm
    out[..., nao.JOINTS.index("RShoulderPitch")] -= arm
    # the hip yaw-pitch is one motor: both legs get the left one's value
    out[..., nao.JOINTS.index("RHipYawPitch")] = out[..., nao.JOINTS.index("LHipYawPitch")]
    return out


def joint_targets(genes: np.ndarray, t_ms: np.ndarray, s: Schedule) -> np.ndarray:
    """Targets ``[P, K, 22]`` (``nao.JOINTS`` order, rad) at the times ``t_ms[K]`` for
    ``genes[P, 14]`` that share the schedule ``s`` (same period), clipped to the NAO's joint
    ranges. Before ``ready_ms`` the crouch blends into the ready pose (smoothstep)."""
    g = np.atleast_2d(np.asarray(genes, dtype=float))
    t_ms = np.asarray(t_ms)
    out = _gait(g, t_ms, s)
    ready_pose = _gait(g, np.array([s.ready_ms]), s)  # [P, 1, 22], amplitude 0
    crouch = nao.pose_vector()[None, None]
    blend = _smoothstep(t_ms.astype(float) / s.ready_ms)[None, :, None]
    out = np.where((t_ms < s.ready_ms)[None, :, None], crouch + blend * (ready_pose - crouch),
                   out)
    return np.clip(out, _RANGE_LO, _RANGE_HI)



def key_times_ms(s: Schedule) -> np.ndarray:
    """The 20 ms pose grid from 0 to the end of the hold."""
    return np.arange(0, s.total_ms + 1, POSE_MS, dtype=np.int64)


def named(genes: np.ndarray) -> dict[str, float]:
    """``{gene name: value}`` of one genome, the period as used (rounded to 40 ms)."""
    out = {n: float(v) for n, v in zip(NAMES, np.asarray(genes, float), strict=True)}
    out["period_used_s"] = float(period_ms(out["period_s"])) / 1000.0
    return out
