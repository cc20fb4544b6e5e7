"""The pieces of :mod:`evomotion.sim.closed_loop` that act per physics step, vectorised over
the running individuals: the servo-latency FIFO, the push forces, the fall test, the bounds of
the targets and the sensors of the initial states."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from evomotion.sim.state import QPOS_OFFSET, STATE_SPEC
from evomotion.sim.worlds import torso_id


class TargetFifo:
    """Per individual, the full target vectors ``[nu]`` of its last ``H`` control steps (a
    ring indexed by control step), so that physics step ``t`` of an individual with latency
    ``d`` uses the target sent at control step ``floor((t - d) / k)``, and ``nominal`` before
    its first target arrives (``t < d``)."""

    def __init__(self, n: int, nominal: np.ndarray, latency_steps: np.ndarray, k: int) -> None:
        self.latency = np.asarray(latency_steps, dtype=np.int64)
        if self.latency.shape != (n,) or (self.latency < 0).any():
            raise ValueError("closed loop: latency_steps must be n integers >= 0")
        self.k, self.nominal = int(k), nominal
        self.depth = math.ceil(int(self.latency.max(initial=0)) / self.k) + 1  # H
        self.ring = np.array(np.broadcast_to(nominal, (n, self.depth, nominal.size)))
        self.delayed = bool((self.latency > 0).any())

    def push(self, rows: np.ndarray, c: int, targets: np.ndarray) -> None:
        """Targets ``[m, nu]`` of ``rows`` sent at control step ``c``."""
        self.ring[rows, c % self.depth] = targets

    def controls(self, rows: np.ndarray, t0: int, nstep: int) -> np.ndarray:
        """``ctrl[m, nstep, nu]`` the servos of ``rows`` act on at physics steps ``t0 + j``."""
        if not self.delayed:  # every step of the period uses the target just sent
            now = self.ring[rows, (t0 // self.k) % self.depth]
            return np.repeat(now[:, None], nstep, axis=1)
        src = t0 + np.arange(nstep)[None] - self.latency[rows][:, None]  # [m, nstep]
        ctrl = self.ring[rows[:, None], (src // self.k) % self.depth]
        ctrl[src < 0] = self.nominal
        return ctrl


@dataclass(frozen=True)
class PushSchedule:
    """Per individual a push: the force ``force_n[n, 3]`` (world frame) on the torso during
    physics steps ``step[n] .. step[n] + push_steps - 1`` (``step`` ``-1``: no push)."""

    force_n: np.ndarray
    step: np.ndarray
    push_steps: int
    torso: int
    nbody: int

    @property
    def any(self) -> bool:
        return bool((self.step >= 0).any())

    @classmethod
    def of(cls, worlds: Sequence, n: int, model: mujoco.MjModel, push_steps: int,
           nstep: int) -> PushSchedule:
        """The pushes of ``worlds`` (``World.push_ns`` N s at ``World.push_time_s``; none
        when ``worlds`` is empty) spread over ``push_steps`` steps; a push starting at or
        after ``nstep`` is not applied."""
        dt = float(model.opt.timestep)
        if not worlds:
            return cls(np.zeros((n, 3)), np.full(n, -1), push_steps, torso_id(model),
                       model.nbody)
        impulse = np.array([w.push_ns for w in worlds], dtype=np.float64)
        step = np.array([int(round(w.push_time_s / dt)) for w in worlds], dtype=np.int64)
        on = impulse.any(axis=1) & (step < nstep) & (step >= 0)
        return cls(impulse / (dt * push_steps), np.where(on, step, -1), int(push_steps),
                   torso_id(model), model.nbody)

    def xfrc(self, rows: np.ndarray, t0: int, nstep: int) -> np.ndarray:
        """``xfrc_applied`` of ``rows`` for physics steps ``t0 + j``: ``[m, nstep, nbody * 6]``."""
        out = np.zeros((rows.size, nstep, self.nbody, 6))
        t = t0 + np.arange(nstep)[None]
        s = self.step[rows][:, None]
        on = (s >= 0) & (t >= s) & (t < s + self.push_steps)
        if on.any():
            out[:, :, self.torso, :3] = np.where(on[..., None], self.force_n[rows][:, None], 0.0)
        return out.reshape(rows.size, nstep, -1)


def first_fallen(states: np.ndarray, fall_height_m: float, fall_tilt_rad: float) -> np.ndarray:
    """Per trajectory of ``states[m, T, nstate]``, the first step whose state is fallen (torso
    lower than ``fall_height_m`` or tilted more than ``fall_tilt_rad``, as
    :func:`evomotion.sim.rollout.fall_step`), ``T`` where none is."""
    q = states[..., QPOS_OFFSET:QPOS_OFFSET + 7]
    x, y = q[..., 4], q[..., 5]
    up_z = 1.0 - 2.0 * (x * x + y * y)
    fallen = (q[..., 2] < fall_height_m) | (up_z < np.cos(fall_tilt_rad))
    return np.where(fallen.any(axis=1), fallen.argmax(axis=1), states.shape[1])


def target_bounds(robot, columns: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) targets of actuator ``columns``: the robot's ``[evolve]`` ranges where
    ``columns`` are its evolved columns, else each actuator's joint range (where limited)
    intersected with its control range (where limited)."""
    if np.array_equal(columns, robot.columns):
        return np.asarray(robot.lower, float), np.asarray(robot.upper, float)
    m = robot.model
    if columns.size and (columns.min() < 0 or columns.max() >= m.nu):
        raise ValueError(f"closed loop: actuator columns must lie in [0, {m.nu})")
    lo, hi = np.full(columns.size, -np.inf), np.full(columns.size, np.inf)
    on_joint = m.actuator_trntype[columns] == mujoco.mjtTrn.mjTRN_JOINT
    joints = m.actuator_trnid[columns, 0]
    limited = on_joint & (m.jnt_limited[joints] > 0)
    lo[limited], hi[limited] = m.jnt_range[joints[limited], 0], m.jnt_range[joints[limited], 1]
    ctrl = m.actuator_ctrllimited[columns] > 0
    lo[ctrl] = np.maximum(lo[ctrl], m.actuator_ctrlrange[columns[ctrl], 0])
    hi[ctrl] = np.minimum(hi[ctrl], m.actuator_ctrlrange[columns[ctrl], 1])
    return lo, hi


def initial_sensors(model: mujoco.MjModel, states: np.ndarray) -> np.ndarray:
    """``sensordata[n, nsensordata]`` of the states ``[n, nstate]`` (``mj_forward`` once per
    distinct state: usually one start for the whole population)."""
    unique, inverse = np.unique(states, axis=0, return_inverse=True)
    data = mujoco.MjData(model)
    out = np.empty((unique.shape[0], model.nsensordata))
    for i, s in enumerate(unique):  # distinct starts, not individuals
        mujoco.mj_setState(model, data, s, STATE_SPEC)
        mujoco.mj_forward(model, data)
        out[i] = data.sensordata
    return out[np.asarray(inverse).reshape(-1)]
