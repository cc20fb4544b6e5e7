"""Closed-loop rollouts of a whole population on MuJoCo Warp (``problem.backend = "warp"``).

The interface and the result of :class:`~evomotion.sim.closed_loop.ClosedLoopSimulator` (the
policy protocol ``policy(rows, obs) -> actions``, observations, actions as clipped offsets
from the nominal pose, latency, pushes, perturbed worlds, early stop, recorded states), with
every world of the population stepped at once by :func:`mujoco_warp.step` on a CUDA device
(or Warp's CPU device). Per control step of ``k`` physics steps
(:mod:`evomotion.sim.warp_closed_loop_kernels`):

1. the observations are built on the device, and their float64 moments accumulated there;
2. the policy: a :class:`~evomotion.sim.warp_policy.PopulationPolicy` of a linear or MLP spec
   runs on the device (every world its own weights); any other callable runs on the host
   (the observations of the running rows copied to numpy, the actions copied back). The
   result says which (``policy_on``);
3. the targets go into a per-world latency ring on the device; ``k`` physics steps read the
   delayed target, apply the push, step, and mark falls. On CUDA each phase is captured once
   as a graph (the clock lives on the device) and replayed.

As on the CPU, MuJoCo's solver warm start is reset at every control step (``mujoco.rollout``
does not carry it), so a trajectory depends only on its world, start and policy: results
are the same whatever the batch. Early stop: fallen worlds stop being recorded at once and,
when the running ones fit a power-of-two batch half the size, are packed into it (host
round trip of the state). Contact buffers that overflow grow and the control step's physics
is redone from its start with the targets already sent (the policy is not called twice).
Precision: float32 (tolerances against the CPU loop in ``tests/sim/test_warp_closed_loop.py``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from evomotion.errors import InputError
from evomotion.sim.closed_loop import (
    ClosedLoopResult,
    Configured,
    Policy,
    _check_sizes,
    _rows,
    configure,
)
from evomotion.sim.closed_loop_parts import PushSchedule, initial_sensors
from evomotion.sim.observations import ObservationSpec
from evomotion.sim.state import QPOS_OFFSET
from evomotion.sim.warp_batch import ClosedLoopBatch, Layout, column_table
from evomotion.sim.warp_memory import bucket_size
from evomotion.sim.warp_policy import on_device
from evomotion.sim.warp_rollout import WarpSimulator
from evomotion.sim.worlds import torso_id


@dataclass(frozen=True)
class WarpClosedLoopResult(ClosedLoopResult):
    """:class:`ClosedLoopResult` and where it ran: ``policy_on`` ``"device"`` (the forward
    pass in Warp kernels) or ``"host"`` (the callable in numpy); ``device`` (Warp's name)."""

    policy_on: str = "host"
    device: str = "cpu"


@dataclass
class _Carry:
    """What a world carries from one device batch to the next (host, per individual)."""

    time: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray
    sensors: np.ndarray
    ring: np.ndarray  # [n, depth, nu]
    fall_step: np.ndarray  # -1: not fallen
    obs_sum: np.ndarray
    obs_sumsq: np.ndarray


class WarpClosedLoopSimulator(Configured):
    """:class:`~evomotion.sim.closed_loop.ClosedLoopSimulator` on MuJoCo Warp (module doc).
    ``nthread`` is accepted and ignored (one device); ``device``, ``deterministic``,
    ``nconmax`` and ``njmax`` as :class:`~evomotion.sim.warp_rollout.WarpSimulator`."""

    backend = "warp"

    def __init__(self, robot, observations: ObservationSpec, control_steps: int,
                 nthread: int = 1, columns: Sequence[int] | None = None,
                 nominal: np.ndarray | None = None, push_steps: int = 1,
                 fall_height_m: float | None = None, fall_tilt_rad: float | None = None, *,
                 device: str = "", deterministic: bool = False, nconmax: int = 16,
                 njmax: int = 0) -> None:
        configure(self, robot, observations, control_steps, nthread, columns, nominal,
                  push_steps, fall_height_m, fall_tilt_rad)
        self.physics = WarpSimulator(self.model, device, deterministic, nconmax, njmax)
        self.wp, self.device = self.physics.wp, self.physics.device
        self.nthread = 1
        self.nstate = self.physics.nstate
        self.dt = float(self.model.opt.timestep)
        self.kind, self.index = column_table(self.observe, robot)
        self.robot_torso = torso_id(self.model)
        self.steps_simulated = 0
        self.regrown = 0
        self._batches: dict[tuple, ClosedLoopBatch] = {}
        self._world_fields: tuple | None = None  # (model ids, models, fields) of the last run

    @property
    def action_size(self) -> int:
        return int(self.columns.size)

    @property
    def observation_size(self) -> int:
        return self.observe.size

    @property
    def spec_command_size(self) -> int:
        return int(self.observe.spec.command_size)

    def close(self) -> None:
        self._batches.clear()

    def __enter__(self) -> WarpClosedLoopSimulator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def record(self) -> dict[str, Any]:
        """What a run folder records about this backend (``physics.json``)."""
        return self.physics.record()

    def run(self, policy: Policy, worlds: Sequence | int, nstep: int, *,
            commands: np.ndarray | None = None, initial_state: np.ndarray | None = None,
            record_states: bool = False, record_targets: bool = False
            ) -> WarpClosedLoopResult:
        """As :meth:`ClosedLoopSimulator.run <evomotion.sim.closed_loop.ClosedLoopSimulator.
        run>`, on the device."""
        worlds = list(worlds) if not isinstance(worlds, int | np.integer) else int(worlds)
        n = len(worlds) if isinstance(worlds, list) else worlds
        nstep = int(nstep)
        if n < 1 or nstep < 1:
            raise InputError(f"closed loop: expected >= 1 individual and step, got {n}, {nstep}")
        listed = worlds if isinstance(worlds, list) else []
        models = np.empty(n, dtype=object)
        models[:] = [w.model for w in listed] if listed else [self.model] * n
        _check_sizes(self.model, models)
        latency = np.array([w.latency_steps for w in listed] if listed else np.zeros(n),
                           dtype=np.int64)
        pushes = PushSchedule.of(listed, n, self.model, self.push_steps, nstep)
        state = _rows(self.robot.state0 if initial_state is None else initial_state,
                      (n, self.nstate), "initial_state")
        cmd = None if commands is None else _rows(commands, (n, self.spec_command_size),
                                                  "commands")
        dev = policy if on_device(policy) else None
        device_policy = dev is not None
        if dev is not None and dev.params.shape[0] != n:
            raise InputError(f"closed loop: the policy holds {dev.params.shape[0]} "
                             f"parameter rows for {n} individuals")
        if dev is not None and (dev.spec.obs_dim, dev.spec.act_dim) != (
                self.observation_size, self.action_size):
            raise InputError(f"closed loop: the policy maps {dev.spec.obs_dim} observations "
                             f"to {dev.spec.act_dim} actions, the robot has "
                             f"{self.observation_size} and {self.action_size}")
        fields, index = self._fields(models)
        nctrl = math.ceil(nstep / self.k)
        layout = Layout(nctrl, math.ceil(int(latency.max(initial=0)) / self.k) + 1,
                        record_states, record_targets, tuple(sorted(fields)), pushes.any,
                        dev.spec if dev is not None else None)
        carry = self._start(state, layout.depth)
        rec = _HostRecords(n, nctrl, state, self.model.nq, self.action_size, layout)
        per_row = _PerRow(latency, pushes, cmd, fields, index, dev)
        alive, c, redo = np.arange(n), 0, False
        while alive.size and c < nctrl:
            b = self._batch(bucket_size(alive.size), layout)
            b.upload(carry, alive, c, self.k, per_row)
            c, redo = self._epoch(b, policy, device_policy, alive, c, nstep, carry, rec, redo)
            alive = alive[carry.fall_step[alive] < 0]
        return rec.result(carry, nstep, self.k, self.dt, "device" if device_policy else "host",
                          self.device)

    def _epoch(self, b: ClosedLoopBatch, policy, device_policy: bool, alive: np.ndarray,
               c: int, nstep: int, carry: _Carry, rec: _HostRecords,
               redo: bool) -> tuple[int, bool]:
        """Control steps from ``c`` in batch ``b`` until the end, until the running worlds fit
        a smaller batch, or until the buffers overflow (then ``(c, True)``: redo its physics)."""
        c0 = c
        live = np.ones(alive.size, dtype=bool)  # the batch rows still running
        while c < self.steps_of(nstep):
            kk = min(self.k, nstep - c * self.k)
            if not redo:
                self._control(b, policy, device_policy, alive, live)
            redo = False
            running, overflow = b.physics(kk, self.physics.mjw)
            self.steps_simulated += b.nworld * kk
            if overflow is not None:
                b.download(carry, rec, alive, c0, c, backup=True)
                self._grow(overflow, b)
                return c, True
            c += 1
            if running == 0 or bucket_size(running) < b.nworld:
                break
            if running < live.sum():
                live = b.running(alive.size)
        b.download(carry, rec, alive, c0, c, backup=False)
        return c, False

    def steps_of(self, nstep: int) -> int:
        """Control steps of an episode of ``nstep`` physics steps."""
        return math.ceil(nstep / self.k)

    def _control(self, b: ClosedLoopBatch, policy, device_policy: bool, alive: np.ndarray,
                 live: np.ndarray) -> None:
        if device_policy:
            b.control_on_device()
            return
        at = np.flatnonzero(live)
        obs = b.observe_to_host()[at].astype(np.float64)
        rows = alive[at]
        rows.flags.writeable = False  # the policy reads the rows, cannot edit ours
        a = np.asarray(policy(rows, obs), dtype=np.float64)
        if a.shape != (at.size, self.columns.size):
            raise ValueError(f"closed loop: the policy returned shape {a.shape}, expected "
                             f"{(at.size, int(self.columns.size))}")
        b.targets_from_host(a, at)

    def _fields(self, models: np.ndarray) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """Batched model fields: every field in which a world's model differs from the
        robot's (none when all worlds are the robot's model), and each world's row in them."""
        distinct = list({id(m): m for m in models}.values())
        if len(distinct) == 1 and distinct[0] is self.model:
            return {}, np.zeros(len(models), dtype=np.int64)
        key = tuple(id(m) for m in distinct)
        if self._world_fields is None or self._world_fields[0] != key or any(
                a is not b for a, b in zip(self._world_fields[1], distinct, strict=True)):
            from evomotion.sim.warp_worlds import differing_fields

            with self.wp.ScopedDevice(self.device):
                fields, _ = differing_fields([self.model, *distinct])
            self._world_fields = (key, distinct, fields)
        position = {id(m): i + 1 for i, m in enumerate(self._world_fields[1])}
        return self._world_fields[2], np.array([position[id(m)] for m in models], np.int64)

    def _start(self, state: np.ndarray, depth: int) -> _Carry:
        n, nq, nv = state.shape[0], self.model.nq, self.model.nv
        q = QPOS_OFFSET
        return _Carry(state[:, 0].copy(), state[:, q:q + nq].copy(),
                      state[:, q + nq:q + nq + nv].copy(), initial_sensors(self.model, state),
                      np.array(np.broadcast_to(self.nominal, (n, depth, self.model.nu))),
                      np.full(n, -1, dtype=np.int64), np.zeros((n, self.observation_size)),
                      np.zeros((n, self.observation_size)))

    def _batch(self, nworld: int, layout: Layout) -> ClosedLoopBatch:
        key = (nworld, layout.key())
        b = self._batches.get(key)
        if b is None:
            stale = [k for k in self._batches if k[1] != layout.key()]
            for k in stale:  # another run's shapes: free its buffers
                del self._batches[k]
            b = ClosedLoopBatch(self, nworld, layout)
            self._batches[key] = b
        return b

    def _grow(self, peak: np.ndarray, b: ClosedLoopBatch) -> None:
        """Enlarge the per-world contact and constraint buffers past what a step used."""
        sim = self.physics
        sim.nconmax = max(2 * sim.nconmax, 2 * int(np.ceil(peak[1] / b.nworld)))
        sim.njmax = max(2 * sim.njmax, 2 * int(peak[0]))
        self.regrown += 1
        self._batches.clear()


@dataclass(frozen=True)
class _PerRow:
    """Per individual: latency, push, commands, world fields and the device policy."""

    latency: np.ndarray
    pushes: PushSchedule
    commands: np.ndarray | None
    fields: dict[str, np.ndarray]
    index: np.ndarray
    policy: Any


class _HostRecords:
    """The result's arrays on the host, filled from each device batch's range of steps."""

    def __init__(self, n: int, nctrl: int, state: np.ndarray, nq: int, a: int,
                 layout: Layout) -> None:
        q = QPOS_OFFSET
        self.torso = np.empty((n, nctrl + 1, 13))
        self.torso[:, 0, :7], self.torso[:, 0, 7:] = state[:, q:q + 7], state[:, q + nq:q + nq + 6]
        self.states = np.empty((n, nctrl + 1, state.shape[1])) if layout.record_states else None
        if self.states is not None:
            self.states[:, 0] = state
        self.targets = np.zeros((n, nctrl, a)) if layout.record_targets else None

    def result(self, carry: _Carry, nstep: int, k: int, dt: float, policy_on: str,
               device: str) -> WarpClosedLoopResult:
        n, nctrl = self.torso.shape[0], self.torso.shape[1] - 1
        fell = carry.fall_step >= 0
        ran = np.where(fell, carry.fall_step // k + 1, nctrl)  # control steps taken
        steps = np.minimum(ran * k, nstep)
        idx = np.minimum(np.arange(nctrl + 1)[None], ran[:, None])
        rows = np.arange(n)[:, None]
        states = None if self.states is None else self.states[rows, idx]
        targets = self.targets
        if targets is not None:  # targets after the fall are never sent: zeros, as on the CPU
            targets = np.where(np.arange(nctrl)[None, :, None] < ran[:, None, None], targets, 0)
        return WarpClosedLoopResult(
            self.torso[rows, idx], fell, np.where(fell, carry.fall_step, nstep), steps,
            ran.astype(np.int64), carry.obs_sum.copy(), carry.obs_sumsq.copy(), k * dt, dt,
            states, targets, policy_on, device)
