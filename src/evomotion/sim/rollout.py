"""Batched open-loop physics with :mod:`mujoco.rollout` and torso-trajectory analysis.

Controls are precomputed in numpy as ``ctrl[batch, nstep, nu]`` (one target per actuator and
physics step); ``mujoco.rollout`` steps every trajectory in C++ threads (one ``MjData`` per
thread), with no Python loop per physics step. Falls, heading and displacement are read back
from the recorded states (``mjSTATE_FULLPHYSICS``: time, qpos, qvel, ...).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from evomotion.sim.state import QPOS_OFFSET, STATE_SPEC


class SegmentedSimulator:
    """What every simulator derives from ``run_with_sensors(init, ctrl)`` (``init``: one
    state or one per row): ``run``, the early-stopped ``run_until`` and ``with`` support."""

    model: mujoco.MjModel
    nstate: int
    #: ``(states[batch, nstep, nstate], sensors[batch, nstep, nsensordata])`` (each subclass's)
    run_with_sensors: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]

    def run(self, initial_state: np.ndarray, ctrl: np.ndarray) -> np.ndarray:
        """``states[batch, nstep, nstate]`` after each step for ``ctrl[batch, nstep, nu]``."""
        return self.run_with_sensors(initial_state, ctrl)[0]

    def run_until(self, initial_state: np.ndarray, ctrl: np.ndarray,
                  stopped: Callable[[np.ndarray], np.ndarray],
                  segment_steps: int) -> tuple[np.ndarray, np.ndarray]:
        """Like ``run_with_sensors``, but in segments of ``segment_steps`` steps: after each
        segment, trajectories for which ``stopped(states_segment) -> bool[batch]`` is true are
        not simulated further; their remaining rows repeat their last state and sensor values.
        (A fallen robot stays fallen, so falls are still found from the recorded states.)"""
        batch, nstep, _ = ctrl.shape
        return rollout_segments(
            lambda rows, start, stop, init: self.run_with_sensors(init, ctrl[rows, start:stop]),
            np.broadcast_to(initial_state, (batch, self.nstate)), nstep,
            self.model.nsensordata, stopped, segment_steps)

    def close(self) -> None:
        """Release threads or device buffers (subclasses)."""

    def __enter__(self):
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class BatchSimulator(SegmentedSimulator):
    """Rolls out batches of control sequences from one initial state with ``nthread`` threads."""

    def __init__(self, model: mujoco.MjModel, nthread: int = 0) -> None:
        self.model = model
        self.nthread = int(nthread) if nthread and nthread > 0 else (os.cpu_count() or 1)
        self.datas = [mujoco.MjData(model) for _ in range(self.nthread)]
        self._runner = mj_rollout.Rollout(nthread=self.nthread) if self.nthread > 1 else None
        self.nstate = mujoco.mj_stateSize(model, STATE_SPEC)
        self.steps_simulated = 0
        self.rollout_seconds = 0.0  # wall time spent inside mujoco.rollout

    def run_with_sensors(self, initial_state: np.ndarray,
                         ctrl: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(``states[batch, nstep, nstate]``, ``sensordata[batch, nstep, nsensordata]``)."""
        ctrl = np.ascontiguousarray(ctrl, dtype=np.float64)
        batch, nstep, _ = ctrl.shape
        init = np.ascontiguousarray(
            np.broadcast_to(initial_state, (batch, self.nstate)), dtype=np.float64)
        t0 = time.perf_counter()
        if self._runner is not None:
            out = self._runner.rollout(self.model, self.datas, init, ctrl, nstep=nstep)
        else:
            out = mj_rollout.rollout(self.model, self.datas[0], init, ctrl, nstep=nstep)
        self.rollout_seconds += time.perf_counter() - t0
        self.steps_simulated += batch * nstep
        return out

    def close(self) -> None:
        if self._runner is not None:
            self._runner.close()
            self._runner = None


def rollout_segments(roll: Callable[[np.ndarray, int, int, np.ndarray],
                                    tuple[np.ndarray, np.ndarray]],
                     initial: np.ndarray, nstep: int, nsensordata: int,
                     stopped: Callable[[np.ndarray], np.ndarray] | None,
                     segment_steps: int) -> tuple[np.ndarray, np.ndarray]:
    """(``states[batch, nstep, nstate]``, ``sensors[batch, nstep, nsensordata]``) of a batch
    rolled out from ``initial[batch, nstate]`` in segments of ``segment_steps`` (one segment
    when ``stopped`` is ``None``): ``roll(rows, start, stop, init_rows) -> (states, sensors)``
    simulates steps ``start:stop`` of the trajectories ``rows``. After each segment,
    trajectories for which ``stopped(segment_states) -> bool[rows]`` is true are not
    simulated further; their remaining rows repeat their last state and sensor values. The
    segments start at the same steps for every trajectory, whatever the batch holds."""
    init = np.array(initial, dtype=np.float64)
    batch, nstate = init.shape
    seg = segment_steps if stopped is not None and segment_steps > 0 else nstep
    states = np.empty((batch, nstep, nstate))
    sensors = np.empty((batch, nstep, nsensordata))
    active = np.arange(batch)
    for start in range(0, nstep, seg):
        stop = min(start + seg, nstep)
        s, d = roll(active, start, stop, np.ascontiguousarray(init[active]))
        states[active, start:stop], sensors[active, start:stop] = s, d
        init[active] = s[:, -1]
        if stopped is None:
            continue
        done = np.asarray(stopped(s), dtype=bool)
        if done.any() and stop < nstep:
            gone = active[done]
            states[gone, stop:] = s[done, -1][:, None]
            sensors[gone, stop:] = d[done, -1][:, None]
            active = active[~done]
        if active.size == 0:
            break
    return states, sensors


def fell(states: np.ndarray, fall_height_m: float, fall_tilt_rad: float) -> np.ndarray:
    """``bool[batch]``: whether each trajectory of ``states[batch, T, nstate]`` is fallen at
    some step (:func:`fall_step` ``< T``), from the torso height and tilt alone (cheap enough
    to ask after every segment of an early-stopped rollout)."""
    q = states[..., QPOS_OFFSET:QPOS_OFFSET + 7]
    x, y = q[..., 4], q[..., 5]  # the quaternion's x and y (w, x, y, z at 3..6)
    up_z = 1.0 - 2.0 * (x * x + y * y)
    return ((q[..., 2] < fall_height_m) | (up_z < np.cos(fall_tilt_rad))).any(axis=-1)


@dataclass
class TorsoTrack:
    """Torso trajectory per rollout: ``xyz[batch, T, 3]``, ``up_z``, ``yaw_rad`` (unwrapped)."""

    xyz: np.ndarray
    up_z: np.ndarray  # z component of the torso's up axis (1 = upright)
    yaw_rad: np.ndarray


def torso_track(states: np.ndarray) -> TorsoTrack:
    """Torso position, uprightness and heading from recorded states (free joint first)."""
    q = states[..., QPOS_OFFSET:QPOS_OFFSET + 7]
    w, x, y, z = (q[..., 3 + i] for i in range(4))
    up_z = 1.0 - 2.0 * (x * x + y * y)
    yaw = np.unwrap(np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)), axis=-1)
    return TorsoTrack(q[..., :3], up_z, yaw)


def fall_step(track: TorsoTrack, fall_height_m: float, fall_tilt_rad: float) -> np.ndarray:
    """Index of the first step at which the robot is fallen (torso lower than
    ``fall_height_m`` or tilted more than ``fall_tilt_rad``), ``nstep`` where it never falls."""
    fallen = (track.xyz[..., 2] < fall_height_m) | (track.up_z < np.cos(fall_tilt_rad))
    nstep = fallen.shape[-1]
    return np.where(fallen.any(axis=-1), fallen.argmax(axis=-1), nstep)


def interpolate_controls(times_s: np.ndarray, values: np.ndarray, dt: float,
                         nstep: int) -> np.ndarray:
    """Linear interpolation of key poses ``values[..., K, nu]`` at ``times_s[K]`` onto the
    physics steps ``t = dt * i``, ``i < nstep`` (the target applied during step ``i``; held
    constant outside the keys).
    Returns ``[..., nstep, nu]``."""
    t = dt * np.arange(nstep)
    idx = np.clip(np.searchsorted(times_s, t, side="right") - 1, 0, len(times_s) - 1)
    nxt = np.minimum(idx + 1, len(times_s) - 1)
    span = np.where(nxt > idx, times_s[nxt] - times_s[idx], 1.0)
    frac = np.clip((t - times_s[idx]) / span, 0.0, 1.0)[:, None]
    return values[..., idx, :] * (1.0 - frac) + values[..., nxt, :] * frac


class ServoWork:
    """Mechanical work of a model's position servos from recorded rollouts:
    ``sum_t sum_j |tau_j qdot_j| dt`` with ``tau = clip(kp (target - q), force range)`` (J)."""

    def __init__(self, model, actuators: np.ndarray | None = None) -> None:
        """``actuators``: the columns of ``ctrl`` to count (default all; they must drive
        joints, e.g. a robot's joint servos without its tendon actuators)."""
        self.columns = None if actuators is None else np.asarray(actuators, dtype=np.int64)
        acts = np.arange(model.nu) if self.columns is None else self.columns
        joints = model.actuator_trnid[acts, 0]
        self.q_cols = _as_slice(QPOS_OFFSET + model.jnt_qposadr[joints])
        self.v_cols = _as_slice(QPOS_OFFSET + model.nq + model.jnt_dofadr[joints])
        self.kp = model.actuator_gainprm[acts, 0].copy()
        limited = model.actuator_forcelimited[acts].astype(bool)[:, None]
        self.force_range = np.where(limited, model.actuator_forcerange[acts],
                                    [-np.inf, np.inf])  # unlimited: no clipping
        self.dt = float(model.opt.timestep)

    def __call__(self, states: np.ndarray, ctrl: np.ndarray, last: np.ndarray) -> np.ndarray:
        """Work ``[P]`` (J) up to and including step ``last[P]``, from ``states[P, T, ns]``
        and the targets the servos received ``ctrl[P, T, nu]``."""
        if self.columns is not None:
            ctrl = ctrl[..., self.columns]
        tau = ctrl - states[..., self.q_cols]  # in place from here: [P, T, nu] is large
        tau *= self.kp
        np.maximum(tau, self.force_range[:, 0], out=tau)
        np.minimum(tau, self.force_range[:, 1], out=tau)
        tau *= states[..., self.v_cols]
        power = np.abs(tau, out=tau).sum(axis=2)  # [P, T] W
        alive = np.arange(power.shape[1])[None] <= np.asarray(last)[:, None]
        return (power * alive).sum(axis=1) * self.dt


def _as_slice(cols: np.ndarray) -> slice | np.ndarray:
    """``cols`` as a slice when they are consecutive (a view instead of a gather)."""
    cols = np.asarray(cols)
    if cols.size and np.all(np.diff(cols) == 1):
        return slice(int(cols[0]), int(cols[-1]) + 1)
    return cols
