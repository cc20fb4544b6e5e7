"""What a closed-loop policy reads: observations declared per robot and task, built for a whole
population at once from the recorded physics states (numpy over ``states[n, nstate]``, no loop
over individuals).

An :class:`ObservationSpec` lists *channels* in the order they appear in the observation
vector; :func:`observation_size` and :func:`observation_names` give its layout for a robot,
and :class:`ObservationBuilder` builds ``obs[n, o]`` from ``STATE_SPEC`` states
(:mod:`evomotion.sim.state`), the ``sensordata`` of the robot's model and per-individual
commands. Channels (units in brackets; the torso is the body of the robot's free joint, its
frame the body frame):

- ``joint_pos`` [rad], ``joint_vel`` [rad/s]: the actuated joints (``joints = "evolved"``: the
  spec's ``[evolve]`` joints in the robot's column order, the default action order of
  :mod:`evomotion.sim.closed_loop`; ``"all"``: every actuator that drives a joint, in
  actuator order; actuators on tendons are skipped);
- ``gravity`` [1]: the unit gravity direction in the torso frame, ``R^T (0, 0, -1)`` from the
  free joint's quaternion (an IMU's accelerometer at rest); ``roll_pitch`` [rad]: the torso's
  roll and pitch (ZYX Euler angles) from the same quaternion;
- ``gyro`` [rad/s]: the torso's angular velocity in its own frame (the free joint's
  ``qvel[3:6]``, which MuJoCo expresses in the body frame); ``torso_velocity`` [m/s]: the
  torso's linear velocity in its own frame, ``R^T v``; ``torso_height`` [m];
- ``foot_contact`` [0/1]: one per foot of the robot (``[feet]`` order), the model's
  ``<foot>_floor`` contact sensor (:mod:`evomotion.sim.robots.build`). Rollouts record
  ``sensordata`` as MuJoCo computed it at the start of the last physics step, so a contact
  is one physics step old (4 ms on the NAO);
- ``phase`` [1]: ``sin`` and ``cos`` of ``2 pi t / phase_period_s`` (``t`` the state's time);
- ``command``: ``command_size`` values given per individual (a velocity command, a target).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from evomotion.errors import InputError
from evomotion.sim.state import QPOS_OFFSET

#: channel -> short description (sizes depend on the robot: see :func:`observation_size`)
CHANNELS = {
    "joint_pos": "actuated joint angles (rad)",
    "joint_vel": "actuated joint velocities (rad/s)",
    "gravity": "gravity direction in the torso frame (unit vector)",
    "roll_pitch": "torso roll and pitch (rad)",
    "gyro": "torso angular velocity in the torso frame (rad/s)",
    "torso_velocity": "torso linear velocity in the torso frame (m/s)",
    "torso_height": "torso height above the world origin (m)",
    "foot_contact": "1 where a foot touches the floor, per foot",
    "phase": "sin and cos of the gait clock",
    "command": "the individual's command vector",
}
JOINT_SETS = ("evolved", "all")


@dataclass(frozen=True)
class ObservationSpec:
    """The channels of an observation vector, in order (see the module doc)."""

    channels: tuple[str, ...] = ("joint_pos", "joint_vel", "gravity", "gyro")
    joints: str = "evolved"  # the actuated joints read: "evolved" | "all"
    phase_period_s: float = 0.0  # the gait clock's period (s), > 0 with "phase"
    command_size: int = 0  # values per individual, >= 1 with "command"

    def validate(self) -> None:
        """One-line :class:`InputError` for no channel, an unknown or repeated one or a bad
        option."""
        if not self.channels:
            raise InputError(f"observation channels: expected at least one of "
                             f"{', '.join(CHANNELS)}, got none")
        for c in self.channels:
            if c not in CHANNELS:
                raise InputError(f"observation channel {c!r} unknown; known: "
                                 f"{', '.join(CHANNELS)}")
        if len(set(self.channels)) != len(self.channels):
            raise InputError(f"observation channels repeated: {list(self.channels)}")
        if self.joints not in JOINT_SETS:
            raise InputError(f"observation joints must be one of {JOINT_SETS}, "
                             f"got {self.joints!r}")
        period = float(self.phase_period_s)
        if "phase" in self.channels and not (np.isfinite(period) and period > 0):
            raise InputError(f"observation phase_period_s must be > 0 s with the phase "
                             f"channel, got {self.phase_period_s}")
        if "command" in self.channels and int(self.command_size) < 1:
            raise InputError("observation command_size must be >= 1 with the command channel")


def observed_actuators(robot, joints: str) -> np.ndarray:
    """Actuator columns whose joints ``joints`` observes, those driving a joint (not a
    tendon): ``"evolved"``: the robot's evolved columns in their order (the closed loop's
    default action order), ``"all"``: every actuator in actuator order."""
    model = robot.model
    cols = np.asarray(robot.columns if joints == "evolved" else np.arange(model.nu), np.int64)
    on_joint = model.actuator_trntype[cols] == mujoco.mjtTrn.mjTRN_JOINT
    return cols[on_joint]


def _channel_names(spec: ObservationSpec, robot, channel: str) -> list[str]:
    model = robot.model
    if channel in ("joint_pos", "joint_vel"):
        joints = model.actuator_trnid[observed_actuators(robot, spec.joints), 0]
        return [f"{channel}:{model.joint(int(j)).name}" for j in joints]
    axes = {"gravity": "xyz", "gyro": "xyz", "torso_velocity": "xyz"}
    if channel in axes:
        return [f"{channel}:{a}" for a in axes[channel]]
    if channel == "roll_pitch":
        return ["roll_pitch:roll", "roll_pitch:pitch"]
    if channel == "torso_height":
        return ["torso_height"]
    if channel == "foot_contact":
        return [f"foot_contact:{f}" for f in robot.feet]
    if channel == "phase":
        return ["phase:sin", "phase:cos"]
    return [f"command:{i}" for i in range(int(spec.command_size))]


def observation_names(spec: ObservationSpec, robot) -> tuple[str, ...]:
    """The name of every column of the observation vector (``channel:item``)."""
    spec.validate()
    return tuple(n for c in spec.channels for n in _channel_names(spec, robot, c))


def observation_size(spec: ObservationSpec, robot) -> int:
    """The length ``o`` of the observation vector of ``spec`` for ``robot``."""
    return len(observation_names(spec, robot))


class ObservationBuilder:
    """Builds ``obs[n, o]`` for ``spec`` and ``robot`` from states, sensors and commands."""

    def __init__(self, spec: ObservationSpec, robot) -> None:
        spec.validate()
        self.spec, self.model = spec, robot.model
        self.names = observation_names(spec, robot)
        self.size = len(self.names)
        self.slices: dict[str, slice] = {}
        start = 0
        for c in spec.channels:
            width = len(_channel_names(spec, robot, c))
            self.slices[c] = slice(start, start + width)
            start += width
        m = robot.model
        joints = m.actuator_trnid[observed_actuators(robot, spec.joints), 0]
        self._q = QPOS_OFFSET + m.jnt_qposadr[joints]
        self._v = QPOS_OFFSET + m.nq + m.jnt_dofadr[joints]
        self._free = QPOS_OFFSET + int(m.jnt_qposadr[0])
        self._free_v = QPOS_OFFSET + m.nq + int(m.jnt_dofadr[0])
        self._contacts = [robot.sensor(f"{f}_floor").start for f in robot.feet]
        self.needs_sensors = "foot_contact" in spec.channels

    def __call__(self, states: np.ndarray, sensors: np.ndarray | None = None,
                 commands: np.ndarray | None = None) -> np.ndarray:
        """``obs[n, o]`` from ``states[n, nstate]``, ``sensors[n, nsensordata]`` (with the
        ``foot_contact`` channel) and ``commands[n, command_size]`` (with ``command``)."""
        out = np.empty((states.shape[0], self.size))
        q = states[:, self._free:self._free + 7]
        w, x, y, z = q[:, 3], q[:, 4], q[:, 5], q[:, 6]
        for c in self.spec.channels:
            s = self.slices[c]
            if c == "joint_pos":
                out[:, s] = states[:, self._q]
            elif c == "joint_vel":
                out[:, s] = states[:, self._v]
            elif c == "gravity":  # -(third row of R): R^T (0, 0, -1)
                out[:, s] = -_third_row(w, x, y, z)
            elif c == "roll_pitch":
                r3 = _third_row(w, x, y, z)
                out[:, s.start] = np.arctan2(r3[:, 1], r3[:, 2])
                out[:, s.start + 1] = np.arcsin(np.clip(-r3[:, 0], -1.0, 1.0))
            elif c == "gyro":
                out[:, s] = states[:, self._free_v + 3:self._free_v + 6]
            elif c == "torso_velocity":
                out[:, s] = _to_body(w, x, y, z, states[:, self._free_v:self._free_v + 3])
            elif c == "torso_height":
                out[:, s.start] = q[:, 2]
            elif c == "foot_contact":
                out[:, s] = _need(sensors, "sensors")[:, self._contacts] > 0
            elif c == "phase":
                angle = 2.0 * np.pi * states[:, 0] / float(self.spec.phase_period_s)
                out[:, s.start], out[:, s.start + 1] = np.sin(angle), np.cos(angle)
            else:
                out[:, s] = _need(commands, "commands")
        return out


def _need(values: np.ndarray | None, what: str) -> np.ndarray:
    if values is None:
        raise ValueError(f"observations: the spec needs {what}")
    return values


def _third_row(w, x, y, z) -> np.ndarray:
    """The third row of the rotation matrix of unit quaternions (``[n, 3]``): ``R^T e_z``."""
    return np.stack([2.0 * (x * z - w * y), 2.0 * (y * z + w * x),
                     1.0 - 2.0 * (x * x + y * y)], axis=1)


def _to_body(w, x, y, z, v: np.ndarray) -> np.ndarray:
    """``R^T v`` for world vectors ``v[n, 3]`` (the conjugate quaternion's rotation)."""
    u = np.stack([-x, -y, -z], axis=1)
    t = 2.0 * np.cross(u, v)
    return v + w[:, None] * t + np.cross(u, t)


def columns_of(names: Sequence[str], channel: str) -> list[int]:
    """Columns of ``names`` (:func:`observation_names`) that belong to ``channel``."""
    return [i for i, n in enumerate(names) if n.split(":", 1)[0] == channel]


#: the sign of each channel's items in the mirror image about the sagittal (x-z) plane:
#: vectors flip y, angular velocities (pseudo-vectors) flip x and z, roll flips
_MIRROR_SIGNS = {"gravity": {"x": 1.0, "y": -1.0, "z": 1.0},
                 "torso_velocity": {"x": 1.0, "y": -1.0, "z": 1.0},
                 "gyro": {"x": -1.0, "y": 1.0, "z": -1.0},
                 "roll_pitch": {"roll": -1.0, "pitch": 1.0}}


def observation_mirror(names: list[str] | tuple[str, ...],
                       joint_mirror: Callable[[str], tuple[str, float]],
                       command_signs: tuple[float, ...] = ()) -> tuple[np.ndarray, np.ndarray]:
    """``(perm, sign)``: column ``i`` of a mirrored observation is ``sign[i] * obs[perm[i]]``
    for the columns ``names`` (:func:`observation_names`). ``joint_mirror(joint) -> (partner,
    sign)`` is the robot's (its ``mirror`` capability); feet named ``left``/``right`` swap; the
    phase maps to itself (the caller shifts it by half a cycle); ``command:i`` keeps its place
    with ``command_signs[i]`` (e.g. a walk's ``(vx, vy, ω)``: ``(1, -1, -1)``)."""
    col = {n: i for i, n in enumerate(names)}
    perm, sign = np.arange(len(names)), np.ones(len(names))
    for i, name in enumerate(names):
        channel, _, item = name.partition(":")
        if channel in ("joint_pos", "joint_vel"):
            partner, s = joint_mirror(item)
            perm[i], sign[i] = col[f"{channel}:{partner}"], s
        elif channel in _MIRROR_SIGNS:
            sign[i] = _MIRROR_SIGNS[channel][item]
        elif channel == "foot_contact":  # "left" and "right" swapped within the foot's name
            other = "right".join(part.replace("right", "left") for part in item.split("left"))
            perm[i] = col[f"{channel}:{other}"]
        elif channel == "command":
            sign[i] = command_signs[int(item)]
    return perm, sign
