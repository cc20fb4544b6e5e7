"""Play a motion (key poses of a robot's channels, :class:`~evomotion.sim.motion.Motion`)
on a robot of :mod:`evomotion.sim.robots`, from its initial state.

The targets between key poses are linear, as Webots interpolates them (:func:`keyframe_targets`,
also the NAO's replay); a channel the motion does not name (or leaves ``*``) holds the robot's
initial pose; after the last key pose the last pose is held.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from evomotion.errors import InputError
from evomotion.sim.motion import Motion
from evomotion.sim.rollout import BatchSimulator, fall_step, torso_track


def keyframe_targets(joints: Sequence[str], pose: np.ndarray, motion: Motion, dt: float,
                     nstep: int) -> tuple[np.ndarray, np.ndarray]:
    """``(first pose[nu], targets[nstep, nu])`` of ``motion`` for the actuators ``joints``
    (``pose``: what a channel the motion leaves out or ``*`` holds): each named channel
    interpolated linearly between its keyframes, as Webots plays a ``.motion``; target ``i``
    is applied from ``t = i dt``; the first pose holds each channel's first keyframe. Channels
    of the motion that ``joints`` lacks are ignored (callers check them when they must)."""
    t_s = motion.times_ms / 1000.0
    t = dt * np.arange(nstep)
    ctrl = np.tile(pose, (nstep, 1))
    first = np.array(pose, dtype=float, copy=True)
    index = {name: j for j, name in enumerate(joints)}
    for name in motion.joints:
        j = index.get(name)
        if j is None:
            continue
        col = motion.column(name)
        ok = ~np.isnan(col)
        if ok.any():
            ctrl[:, j] = np.interp(t, t_s[ok], col[ok])
            first[j] = col[ok][0]
    return first, ctrl


def motion_controls(robot, motion: Motion, dt: float, nstep: int) -> np.ndarray:
    """Actuator targets ``[nstep, nu]`` of ``robot`` (:func:`keyframe_targets`); a channel
    that is not the robot's is one line."""
    unknown = [j for j in motion.joints if j not in robot.joints]
    if unknown:
        raise InputError(f"the motion names {unknown[0]!r}, not a channel of robot "
                         f"{robot.name!r} ({', '.join(robot.joints)})")
    return keyframe_targets(robot.joints, robot.pose, motion, dt, nstep)[1]


def play_motion(robot, motion: Motion, hold_s: float = 1.0, nthread: int = 1) -> dict:
    """Play ``motion`` then hold ``hold_s``: the summary (displacement in the start heading's
    frame [m], heading change [rad], fell, fall time) and the trajectory (``qpos``, ``dt``)."""
    model = robot.model
    dt = float(model.opt.timestep)
    nstep = int(np.ceil((motion.duration_s + hold_s) / dt))
    ctrl = motion_controls(robot, motion, dt, nstep)
    with BatchSimulator(model, nthread) as sim:
        states = sim.run(robot.state0, ctrl[None])
    track = torso_track(states)
    fall = int(fall_step(track, robot.fall_height_m, robot.fall_tilt_rad)[0])
    yaw0 = float(track.yaw_rad[0, 0])
    d = track.xyz[0, -1, :2] - track.xyz[0, 0, :2]
    c, s = np.cos(yaw0), np.sin(yaw0)
    summary = {
        "robot": robot.name,
        "displacement_m": [float(c * d[0] + s * d[1]), float(-s * d[0] + c * d[1])],
        "heading_change_rad": float(track.yaw_rad[0, -1] - yaw0),
        "fell": fall < nstep,
        "fall_time_s": float((fall + 1) * dt) if fall < nstep else None,
    }
    return {"summary": summary, "qpos": states[0, :, 1:1 + model.nq], "dt": dt}


def robot_camera(robot, back: float = 2.6, least_m: float = 1.1) -> str:
    """The render camera for ``robot``: follow its torso from ``back`` times the torso's
    start height away (at least ``least_m``), looking at 0.6 of that height."""
    height = float(robot.state0[3])  # time, then the free joint's x, y, z
    return f"follow={robot.spec.torso},{max(least_m, back * height):.2f},{0.6 * height:.2f}"
