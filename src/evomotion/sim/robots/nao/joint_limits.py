"""A real NAO's joint limits and the checks a motion must pass before it goes to one.

Ranges (rad): Aldebaran "H25 - Joints" V5 & V4 (``doc.aldebaran.com/2-5/family/nao_h25/
joints_h25.html``), in radians as gathered in ``/work/shared/reference/nao-h25.md`` section
1.4 (they agree with B-Human ``jointLimits.cfg``; the MJCF ``sim/robots/nao/nao_h25.xml`` holds the
same values rounded to 6 digits, but only for its 22 joints). The hands are 0 (closed) to 1
(open), not angles.

Speeds (rad/s, joint side): the no-load speeds of the V3.x motors, motor no-load speed over
the reduction ratio (Aldebaran "H25 - Motors - V3.2", ``doc.aldebaran.com/1-14/family/nao_h25/
motors_h25_v32.html``, and the V3.3 motor tables; ``/work/shared/reference/walking.md``
section 3): RE-Max 24 (8000 rpm) / 201.3 = 4.16 (HipYawPitch, HipRoll, AnkleRoll), / 130.85 =
6.40 (HipPitch, KneePitch, AnklePitch); RE-Max 17 (11900 rpm) / 150.27 = 8.27 (HeadYaw,
ShoulderPitch, ElbowYaw), / 173.22 = 7.19 (HeadPitch, ShoulderRoll, ElbowRoll), / 50.61 = 24.6
(WristYaw, V3.3 on). The V6 leg motors are faster (4.53 / 6.96 rad/s, NAO6 datasheet), so legs
within these limits fit a V6 too; the V6 head and arm motors are listed at 6.5-7.9 rad/s, so
for a V6 moving its arms fast use a margin of about 0.8. A no-load speed is an upper bound (a
loaded joint is slower), hence ``speed_margin``: every limit times it, in (0, 1]. The hands'
opening has no published speed and is not speed-checked.

``LHipYawPitch`` and ``RHipYawPitch`` are one motor; on conflicting commands the left one
wins (NAOqi "Joint control", ``cs.cmu.edu/~cga/nao/doc/reference-documentation/naoqi/motion/
control-joint.html``). A motion giving both with different values is an **error** here: the
robot would not do what was simulated.
"""

from __future__ import annotations

import math

import numpy as np

from evomotion.errors import InputError
from evomotion.sim.motion import Motion

#: Published NAO H25 V5 range of every joint a motion may drive (rad; hands 0..1).
JOINT_RANGES: dict[str, tuple[float, float]] = {
    "HeadYaw": (-2.085668, 2.085668), "HeadPitch": (-0.671952, 0.514872),
    "LShoulderPitch": (-2.085668, 2.085668), "RShoulderPitch": (-2.085668, 2.085668),
    "LShoulderRoll": (-0.314159, 1.326450), "RShoulderRoll": (-1.326450, 0.314159),
    "LElbowYaw": (-2.085668, 2.085668), "RElbowYaw": (-2.085668, 2.085668),
    "LElbowRoll": (-1.544616, -0.034907), "RElbowRoll": (0.034907, 1.544616),
    "LWristYaw": (-1.823869, 1.823869), "RWristYaw": (-1.823869, 1.823869),
    "LHand": (0.0, 1.0), "RHand": (0.0, 1.0),
    "LHipYawPitch": (-1.145285, 0.740718), "RHipYawPitch": (-1.145285, 0.740718),
    "LHipRoll": (-0.379435, 0.790460), "RHipRoll": (-0.790460, 0.379435),
    "LHipPitch": (-1.535890, 0.483980), "RHipPitch": (-1.535890, 0.483980),
    "LKneePitch": (-0.092328, 2.112547), "RKneePitch": (-0.102974, 2.120051),
    "LAnklePitch": (-1.189442, 0.922581), "RAnklePitch": (-1.186300, 0.932006),
    "LAnkleRoll": (-0.397761, 0.768992), "RAnkleRoll": (-0.768992, 0.397935),
}
#: An angle this close outside a range still passes (rounded radians; the encoders resolve 0.1 deg).
RANGE_TOL_RAD = 1e-4

_SPEEDS = {"HipYawPitch": 4.16, "HipRoll": 4.16, "AnkleRoll": 4.16, "HipPitch": 6.40,
           "KneePitch": 6.40, "AnklePitch": 6.40, "ShoulderPitch": 8.27, "ElbowYaw": 8.27,
           "ShoulderRoll": 7.19, "ElbowRoll": 7.19, "WristYaw": 24.6}
#: No-load joint speed of the V3.x motors (rad/s), per joint (hands: none published).
SPEED_LIMITS: dict[str, float] = {"HeadYaw": 8.27, "HeadPitch": 7.19,
                                  **{s + p: v for p, v in _SPEEDS.items() for s in "LR"}}


class LimitError(InputError):
    """A motion a real NAO cannot play: ``str()`` names the joint, time, value and limit."""


def _first(mask: np.ndarray) -> tuple[int, int, int]:
    """(keyframe, joint, count) of the first True of ``mask[K, N]`` in time order."""
    k, j = np.argwhere(mask)[0]
    return int(k), int(j), int(mask.sum())


def _more(n: int, what: str) -> str:
    return f" ({n - 1} more {what})" if n > 1 else ""


def _check_margin(speed_margin: float) -> None:
    if not (math.isfinite(speed_margin) and 0.0 < speed_margin <= 1.0):
        raise InputError(f"export: expected a speed margin in (0, 1], got {speed_margin:g}")


def check_ranges(motion: Motion, clip: bool = False) -> tuple[Motion, int]:
    """The motion (clipped when ``clip``) and how many angles were clipped; else
    :class:`LimitError` for the first angle outside its joint's range."""
    lo, hi = (np.array([JOINT_RANGES[n][i] for n in motion.joints]) for i in (0, 1))
    v = motion.values
    with np.errstate(invalid="ignore"):
        out = (v < lo - RANGE_TOL_RAD) | (v > hi + RANGE_TOL_RAD)
        outside = (v < lo) | (v > hi)
    if not clip:
        if out.any():
            k, j, n = _first(out)
            name = motion.joints[j]
            raise LimitError(f"export: {name} at {motion.times_ms[k] / 1000:.3f} s is "
                             f"{v[k, j]:.4f}, outside its range {lo[j]:.4f}..{hi[j]:.4f} "
                             f"(NAO H25 V5){_more(n, 'angles out of range')}; "
                             "--clip clips to the ranges")
        return motion, 0
    clipped = np.where(np.isnan(v), v, np.clip(v, lo, hi))
    return (Motion(motion.joints, motion.times_ms.copy(), clipped, list(motion.pose_names)),
            int(outside.sum()))


def check_hip_yaw_pitch(motion: Motion) -> None:
    """:class:`LimitError` where both hip yaw-pitch joints are given and differ."""
    if not {"LHipYawPitch", "RHipYawPitch"} <= set(motion.joints):
        return
    left, right = motion.column("LHipYawPitch"), motion.column("RHipYawPitch")
    with np.errstate(invalid="ignore"):
        bad = np.abs(left - right) > RANGE_TOL_RAD
    if bad.any():
        k = int(np.argmax(bad))
        raise LimitError(f"export: LHipYawPitch {left[k]:.4f} and RHipYawPitch {right[k]:.4f} "
                         f"differ at {motion.times_ms[k] / 1000:.3f} s; they are one motor and "
                         "the robot follows LHipYawPitch")


def check_speeds(motion: Motion, speed_margin: float = 1.0) -> None:
    """:class:`LimitError` for the first joint that moves faster than ``speed_margin`` times
    its motor's limit between two consecutive keyframes where it is given (linear
    interpolation, as ALMotion and Webots' player move)."""
    _check_margin(speed_margin)
    t = motion.times_ms / 1000.0
    worst: tuple[float, int, str, float, float] | None = None
    count = 0
    for j, name in enumerate(motion.joints):
        if name not in SPEED_LIMITS:
            continue
        given = ~np.isnan(motion.values[:, j])
        tj, vj = t[given], motion.values[given, j]
        speed = np.abs(np.diff(vj)) / np.diff(tj)
        limit = speed_margin * SPEED_LIMITS[name]
        fast = np.nonzero(speed > limit * (1 + 1e-9))[0]
        count += fast.size
        if fast.size and (worst is None or tj[fast[0] + 1] < worst[0]):
            i = int(fast[0])
            worst = (float(tj[i + 1]), j, name, float(speed[i]), limit)
    if worst is not None:
        when, _, name, speed, limit = worst
        scaled = (f" ({speed_margin:g} x {SPEED_LIMITS[name]:.2f})" if speed_margin < 1 else "")
        raise LimitError(f"export: {name} at {when:.3f} s moves {speed:.3f} rad/s, above its "
                         f"{limit:.2f} rad/s limit{scaled}{_more(count, 'too fast moves')}")


def check_motion(motion: Motion, *, clip: bool = False,
                 speed_margin: float = 1.0) -> tuple[Motion, int]:
    """All real-robot checks: ranges (or clip to them), the shared hip motor, speeds.
    Returns the motion to export and the number of clipped angles."""
    _check_margin(speed_margin)
    motion, clipped = check_ranges(motion, clip)
    check_hip_yaw_pitch(motion)
    check_speeds(motion, speed_margin)
    return motion, clipped
