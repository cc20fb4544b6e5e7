"""A biped's standing stance, widened, staggered, lowered and leaned from its spec pose, soles
flat.

Defined on the robot's ``[gait]`` roles (one channel per leg, left then right, each signed so
that + hip_pitch moves the thigh forward, + knee flexes, + ankle_pitch lifts the toes,
+ hip_roll moves the foot towards +y, ankle_roll turns about +x; :data:`.robots.spec
.GAIT_ROLES`), so it means the same on every biped. Changes from the spec's ``[pose]`` (rad):

- ``width_rad`` w: each hip rolls its foot outwards by w (left +w, right -w) and the ankle rolls
  back by as much, so the sole keeps its roll (the support polygon widens by about
  ``2 w x leg length``);
- ``stagger_rad`` s: the left thigh swings forward by s and the right one back by s, each ankle
  pitching the other way by as much (the left foot ahead, the right behind: the polygon
  lengthens);
- ``crouch_rad`` c: hips +c, knees +2c, ankles +c (lower, the torso kept upright);
- ``lean_rad`` l: both thighs forward by l relative to the torso (hips +l), and at rest the
  whole robot turned so that the soles lie flat again: the torso pitched forward by about l,
  the centre of mass moved forward over the feet (on the NAO in humanoid-balance's stance,
  about 7 mm per 0.1 rad; its soles, their mean flat, roll by 0.3 deg either way at 0.2 rad,
  the thigh's pitch axis being turned by the hip roll of the width).

Apart from the lean, each sole keeps its pitch (hip_pitch - knee + ankle_pitch is unchanged)
and its roll (hip_roll + ankle_roll is unchanged), exactly where only pitch joints summing to
zero lie between the two roll joints: the NAO's and the OP3's soles stay within 0.01 deg of
their spec pose's (tested); the dm humanoid's hip yaw joint lies between, and its soles tilt by
2.1 deg at a width of 0.3 rad. Pushes that topple a biped standing in its narrow spec pose (the
NAO's soles are 9 cm wide, 5 cm apart) are what a wider base is for (docs/humanoid-balance.md).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from evomotion.errors import InputError
from evomotion.sim.closed_loop_parts import target_bounds
from evomotion.sim.robots.build import Robot
from evomotion.sim.state import state_qpos_all
from evomotion.sim.worlds import torso_id

ROLES = ("hip_pitch", "knee", "ankle_pitch", "hip_roll", "ankle_roll")


def stance_pose(robot: Robot, width_rad: float = 0.0, stagger_rad: float = 0.0,
                crouch_rad: float = 0.0, where: str = "stance", *,
                lean_rad: float = 0.0) -> np.ndarray:
    """The targets ``[nu]`` of the stance (module doc); the spec pose itself, bit for bit, when
    all four are 0. One :class:`InputError` line (naming ``where``) for a robot without the
    biped gait roles or a stance beyond a joint's range."""
    pose = np.array(robot.pose, dtype=float)
    if width_rad == 0.0 and stagger_rad == 0.0 and crouch_rad == 0.0 and lean_rad == 0.0:
        return pose
    missing = [r for r in ROLES if r not in robot.gait]
    if robot.gait_kind != "biped" or missing:
        raise InputError(f"{where}: robot {robot.name!r} declares no biped [gait] roles "
                         f"({', '.join(missing) or 'not a biped'} missing) to place a "
                         "stance with; set the stance's keys to 0 (the spec pose)")
    change = {
        "hip_roll": (width_rad, -width_rad),
        "ankle_roll": (-width_rad, width_rad),
        "hip_pitch": (crouch_rad + stagger_rad + lean_rad, crouch_rad - stagger_rad + lean_rad),
        "knee": (2.0 * crouch_rad, 2.0 * crouch_rad),
        "ankle_pitch": (crouch_rad - stagger_rad, crouch_rad + stagger_rad),
    }
    for role, per_leg in change.items():
        for (column, sign), delta in zip(robot.gait[role], per_leg, strict=True):
            pose[column] += sign * delta
    lo, hi = target_bounds(robot, np.arange(robot.model.nu))  # joint and control ranges
    lo[robot.columns] = np.maximum(lo[robot.columns], robot.lower)  # the [evolve] ranges
    hi[robot.columns] = np.minimum(hi[robot.columns], robot.upper)
    bad = np.flatnonzero((pose < lo) | (pose > hi))
    if bad.size:
        a = int(bad[0])
        raise InputError(f"{where}: the stance puts {robot.joints[a]} at {pose[a]:.3f} rad, "
                         f"outside its range [{lo[a]:.3f}, {hi[a]:.3f}]")
    return pose


def with_stance(robot: Robot, width_rad: float = 0.0, stagger_rad: float = 0.0,
                crouch_rad: float = 0.0, where: str = "stance", *,
                lean_rad: float = 0.0) -> Robot:
    """``robot`` standing in the stance: its ``pose`` and its initial state at rest in it
    (the lowest sole ``clearance_m`` above the floor, as the spec pose's; with a lean, the
    robot turned so that its soles lie flat, its lowest sole site as high as in the spec
    pose's initial state); the robot itself when all four are 0. A stance
    that widens a robot with feet ``left`` and ``right`` but brings its soles closer
    (``[gait]`` listing the right leg first) is one line."""
    pose = stance_pose(robot, width_rad, stagger_rad, crouch_rad, where, lean_rad=lean_rad)
    if np.array_equal(pose, robot.pose):
        return robot
    state0 = robot.state_at(pose)
    if lean_rad != 0.0:
        state0 = _soles_flat(robot, state0, where)
    if width_rad > 0 and {"left", "right"} <= set(robot.feet) and \
            _feet_apart_m(robot, state0) <= _feet_apart_m(robot, robot.state0):
        raise InputError(f"{where}: the stance moves robot {robot.name!r}'s feet together, "
                         "not apart: its [gait] roles must list the left leg's channel "
                         "first, then the right's")
    return dataclasses.replace(robot, pose=pose, state0=state0)


def _soles_flat(robot: Robot, state: np.ndarray, where: str = "stance") -> np.ndarray:
    """``state`` with the whole robot turned about its root so that the mean of its soles'
    normals points up, then raised or lowered so that its lowest sole stands as high as in the
    robot's own initial state (flat soles, the spec's clearance)."""
    import mujoco

    m = robot.model
    d = mujoco.MjData(m)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS

    def soles(st: np.ndarray) -> tuple[np.ndarray, float]:
        mujoco.mj_setState(m, d, st, spec)
        mujoco.mj_kinematics(m, d)
        sites = [d.site(robot.sole_site(f)) for f in robot.feet]
        return (np.mean([s.xmat.reshape(3, 3)[:, 2] for s in sites], axis=0),
                min(float(s.xpos[2]) for s in sites))

    low = soles(robot.state0)[1]
    normal = soles(state)[0]
    normal /= np.linalg.norm(normal)
    axis = np.cross(normal, [0.0, 0.0, 1.0])
    turn = np.zeros(4)
    mujoco.mju_axisAngle2Quat(turn, axis / max(np.linalg.norm(axis), 1e-12),
                              float(np.arccos(np.clip(normal[2], -1.0, 1.0))))
    free = [j for j in range(m.njnt) if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
    if not free:
        raise InputError(f"{where}: robot {robot.name!r} has no free root joint to lean")
    out = np.array(state, dtype=float)
    q = state_qpos_all(m, out)  # a view: writing q writes out
    a = int(m.jnt_qposadr[free[0]])
    quat = np.zeros(4)
    mujoco.mju_mulQuat(quat, turn, q[a + 3:a + 7].copy())
    q[a + 3:a + 7] = quat
    q[a + 2] += low - soles(out)[1]
    return out


def _feet_apart_m(robot: Robot, state: np.ndarray) -> float:
    """How far the left sole lies to the left of the right one (m, along the torso's y axis)
    with the robot in ``state``."""
    import mujoco

    m = robot.model
    d = mujoco.MjData(m)
    mujoco.mj_setState(m, d, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    mujoco.mj_kinematics(m, d)
    left, right = (d.site(robot.sole_site(f)).xpos for f in ("left", "right"))
    y_axis = d.xmat[torso_id(m)].reshape(3, 3)[:, 1]
    return float((left - right) @ y_axis)
