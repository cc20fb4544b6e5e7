"""Play an exported walk controller on one robot inside any MuJoCo model that holds it (the NAO
beside a ball, say): the robot-side loop that ``policy.json`` describes, run in simulation.

A policy-search run (humanoid-walk, humanoid-balance) leaves ``policy.npz`` (raw
observation -> action, normalisation inside; :mod:`evomotion.core.policies.export`) and
``policy.json`` (the observation columns in order, the gait clock's period, the control period,
the driven joints with their nominal pose and bounds, the follower joint, the command ranges
and ramp). Every control period :meth:`PolicyPlayer.step` reads each column from ``MjData``
exactly as the training's :class:`~evomotion.sim.observations.ObservationBuilder` builds it
from a state:

- ``joint_pos:J`` / ``joint_vel:J``: the joint's ``qpos`` / ``qvel``;
- ``gravity:x|y|z``: ``R^T (0, 0, -1)`` with ``R`` the free joint's orientation;
  ``roll_pitch``; ``gyro:x|y|z``: the free joint's angular velocity (body frame);
  ``torso_velocity``: its linear velocity in the body frame; ``torso_height``;
- ``foot_contact:F``: 1 while the contact sensor the caller names for foot ``F`` finds one;
- ``phase:sin|cos``: the gait clock, ``2 pi (t - t_start) / period`` (the walk's own time: a
  training episode starts its clock at 0);
- ``command:i``: the command, rate-limited as training ramps it (a change of a whole range
  takes ``command_ramp_s``).

A walk controller evolved with a capture step (``policy.json``'s ``layers.capture_step``:
the NAO's) runs it on top of the policy, as the NAOqi runner does
(:mod:`evomotion.sim.robots.nao.naoqi_capture_step`; its state restarts with :meth:`start`).
Then ``target = clip(nominal + action, lower, upper)`` for the driven joints, the follower
copies its leader, every other actuator holds ``nominal_pose_all_actuators``; the targets are
held for ``control_steps`` physics steps. Actuators are matched by name, so the model may hold
other bodies (a ball) beside the robot.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from evomotion.core.policies.export import read_policy_npz
from evomotion.errors import FileFormatError, InputError
from evomotion.sim.control_period import whole_steps
from evomotion.textio import read_json

MAX_JSON_BYTES = 1 << 20
MAX_CONTROL_STEPS = 1000  # physics steps per control period (seconds at the NAO's 4 ms)


def _floats(info: dict, key: str, n: int, path: Path) -> np.ndarray:
    v = info.get(key)
    if (not isinstance(v, list) or len(v) != n
            or not all(isinstance(x, int | float) and not isinstance(x, bool) for x in v)):
        raise FileFormatError(path, None, f"key {key!r}: a list of {n} numbers")
    return np.asarray(v, dtype=float)


class PolicyPlayer:
    """The controller of the run folder ``folder`` playing on ``model`` (see the module doc);
    ``contact_sensors``: foot name -> the name of a contact sensor of ``model`` (its first
    value is the number of contacts found)."""

    def __init__(self, folder: str | Path, model: mujoco.MjModel,
                 contact_sensors: dict[str, str] | None = None) -> None:
        folder = Path(folder)
        jpath = folder / "policy.json"
        info = read_json(jpath, "controller description (policy.json)", MAX_JSON_BYTES)
        if not isinstance(info, dict):
            raise FileFormatError(jpath, None, "a JSON object")
        self.layer_record = self._layer_record(info, jpath)
        self._jpath = jpath
        self.policy = read_policy_npz(folder / "policy.npz")
        names = info.get("observations")
        if not isinstance(names, list) or len(names) != self.policy.spec.obs_dim:
            raise FileFormatError(jpath, None, f"key 'observations': {self.policy.spec.obs_dim} "
                                               "column names (as policy.npz's observations)")
        self.model = model
        joints = info.get("joints")
        a = self.policy.spec.act_dim
        if not isinstance(joints, list) or len(joints) != a:
            raise FileFormatError(jpath, None, f"key 'joints': {a} joint names")
        self.columns = np.array([self._actuator(str(j), jpath) for j in joints])
        self.nominal_driven = _floats(info, "nominal_rad", a, jpath)
        self.lower = _floats(info, "lower_rad", a, jpath)
        self.upper = _floats(info, "upper_rad", a, jpath)
        pose = info.get("nominal_pose_all_actuators", {})
        if not isinstance(pose, dict):
            raise FileFormatError(jpath, None, "key 'nominal_pose_all_actuators': an object")
        self.nominal = np.zeros(model.nu)
        for name, v in pose.items():
            if isinstance(v, int | float) and not isinstance(v, bool):
                self.nominal[self._actuator(str(name), jpath)] = float(v)
        self.nominal[self.columns] = self.nominal_driven
        followers = info.get("followers") or {}
        if not isinstance(followers, dict) or not all(isinstance(v, str) for v in
                                                      followers.values()):
            raise FileFormatError(jpath, None, "key 'followers': an object of actuator names "
                                               "(follower: the actuator it copies)")
        self.followers = [(self._actuator(str(f), jpath), self._actuator(lead, jpath))
                          for f, lead in followers.items()]
        self.period_s = self._number(info, "phase_period_s", jpath)
        self.control_dt = self._number(info, "control_period_s", jpath)
        steps = whole_steps(self.control_dt, model.opt.timestep, MAX_CONTROL_STEPS)
        if steps is None:
            raise FileFormatError(jpath, None, f"key 'control_period_s': a whole number (1 to "
                                  f"{MAX_CONTROL_STEPS}) of the model's {model.opt.timestep} s "
                                  f"physics steps, got {self.control_dt!r}")
        self.control_steps = steps
        ranges = info.get("command_ranges") or {}
        ok = isinstance(ranges, dict) and all(
            isinstance(v, list) and len(v) == 2 and all(
                isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)
                for x in v) and v[0] <= v[1] for v in ranges.values())
        if not ok:
            raise FileFormatError(jpath, None, "key 'command_ranges': an object of [low, high] "
                                               "pairs")
        #: each command component's (low, high), in the order of ``policy.json``
        self.command_ranges = {str(k): (float(v[0]), float(v[1])) for k, v in ranges.items()}
        self.command_span = np.array([hi - lo for lo, hi in self.command_ranges.values()])
        ramp = info.get("command_ramp_s") or 0.0
        if not isinstance(ramp, int | float) or isinstance(ramp, bool) or ramp < 0:
            raise FileFormatError(jpath, None, "key 'command_ramp_s': a number >= 0")
        self.ramp_s = float(ramp)
        self.readers = [self._reader(str(n), contact_sensors or {}, jpath) for n in names]
        self.command = np.zeros(self.command_span.size)
        self.t_start = 0.0
        self.layer: Any = None
        self._layer_args = ([str(n) for n in names], [str(j) for j in joints],
                            [float(v) for v in self.nominal_driven], self.control_dt)
        self._new_layer()

    @staticmethod
    def _layer_record(info: dict, path: Path) -> dict | None:
        """``policy.json``'s ``layers``: only a capture step with its whole record."""
        layers = info.get("layers") or {}
        if not isinstance(layers, dict) or set(layers) - {"capture_step"}:
            raise InputError(f"{path}: key 'layers': this player runs a capture step "
                             f"(capture_step) only, got {layers!r:.80}")
        from evomotion.sim.robots.nao.naoqi_capture_step import KEYS

        record = layers.get("capture_step")
        if record is None:
            return None
        if not isinstance(record, dict) or not set(record) >= set(KEYS):
            raise FileFormatError(path, None, "key 'layers.capture_step': an object with "
                                  f"{', '.join(sorted(KEYS))} (a run folder "
                                  "from before 2026-12-06's 15th session lacks them)")
        return record

    def _new_layer(self) -> None:
        if self.layer_record is None:
            return
        from evomotion.sim.robots.nao.naoqi_capture_step import CaptureStep

        try:
            self.layer = CaptureStep(self.layer_record, *self._layer_args)
        except ValueError as e:  # check()'s line, or a missing observation or joint
            raise InputError(f"{self._jpath}: layers: {e}"[:400]) from None

    def _actuator(self, name: str, path: Path) -> int:
        i = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_ACTUATOR, name)
        if i < 0:
            raise InputError(f"{path}: actuator {name!r} is not in the simulated model")
        return int(i)

    @staticmethod
    def _number(info: dict, key: str, path: Path) -> float:
        v = info.get(key)
        if not isinstance(v, int | float) or isinstance(v, bool) or not v > 0:
            raise FileFormatError(path, None, f"key {key!r}: a number > 0")
        return float(v)

    def _reader(self, name: str, contacts: dict[str, str], path: Path):
        m = self.model
        channel, _, item = name.partition(":")
        free_q = int(m.jnt_qposadr[0])
        free_v = int(m.jnt_dofadr[0])
        axes = {"x": 0, "y": 1, "z": 2}
        if channel in ("joint_pos", "joint_vel"):
            j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, item)
            if j < 0:
                raise InputError(f"{path}: joint {item!r} is not in the simulated model")
            adr = int(m.jnt_qposadr[j] if channel == "joint_pos" else m.jnt_dofadr[j])
            return (lambda d: d.qpos[adr]) if channel == "joint_pos" else (lambda d: d.qvel[adr])
        if channel == "gravity" and item in axes:
            return lambda d, i=axes[item]: -_rotation(d, free_q)[2, i]
        if channel == "gyro" and item in axes:
            return lambda d, i=axes[item]: d.qvel[free_v + 3 + i]
        if channel == "torso_velocity" and item in axes:
            return lambda d, i=axes[item]: (_rotation(d, free_q).T
                                            @ d.qvel[free_v:free_v + 3])[i]
        if channel == "roll_pitch" and item in ("roll", "pitch"):
            def roll_pitch(d, roll=item == "roll"):
                r3 = _rotation(d, free_q)[2]
                return (math.atan2(r3[1], r3[2]) if roll
                        else math.asin(float(np.clip(-r3[0], -1.0, 1.0))))
            return roll_pitch
        if channel == "torso_height":
            return lambda d: d.qpos[free_q + 2]
        if channel == "foot_contact" and item in contacts:
            s = m.sensor(contacts[item])
            adr = int(s.adr[0])
            return lambda d: float(d.sensordata[adr] > 0)
        if channel == "phase" and item in ("sin", "cos"):
            f = math.sin if item == "sin" else math.cos
            return lambda d: f(2.0 * math.pi * (d.time - self.t_start) / self.period_s)
        if channel == "command" and item.isdigit() and int(item) < self.command_span.size:
            return lambda d, i=int(item): self.command[i]
        raise InputError(f"{path}: observation {name!r} cannot be read by the player "
                         "(no such channel, or no contact sensor named for that foot)")

    def start(self, data: mujoco.MjData) -> None:
        """The gait clock starts now; the command is standing."""
        self.t_start = float(data.time)
        self.command = np.zeros(self.command_span.size)
        self._new_layer()

    def observe(self, data: mujoco.MjData) -> np.ndarray:
        return np.array([r(data) for r in self.readers], dtype=float)

    def targets(self, data: mujoco.MjData, command: Any = None) -> np.ndarray:
        """All ``nu`` servo targets for the next control period under ``command`` (moved
        towards it by at most one control period of the ramp)."""
        if command is not None and self.command.size:
            want = np.asarray(command, dtype=float).reshape(self.command.size)
            step = (self.command_span * self.control_dt / self.ramp_s if self.ramp_s > 0
                    else np.full(self.command.size, np.inf))
            self.command = self.command + np.clip(want - self.command, -step, step)
        p = self.policy
        obs = self.observe(data)
        action = p.spec.act_one(p.params, obs, p.obs_mean, p.obs_std)
        if self.layer is not None:
            action = np.array(self.layer(obs.tolist(), action.tolist()))
        action = np.where(np.isnan(action), 0.0, action)
        out = self.nominal.copy()
        out[self.columns] = np.clip(self.nominal_driven + action, self.lower, self.upper)
        for follower, leader in self.followers:
            out[follower] = out[leader]
        return out


def _rotation(data: mujoco.MjData, free_q: int) -> np.ndarray:
    mat = np.empty(9)
    mujoco.mju_quat2Mat(mat, data.qpos[free_q + 3:free_q + 7])
    return mat.reshape(3, 3)
