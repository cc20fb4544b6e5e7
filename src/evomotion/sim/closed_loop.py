"""Closed-loop rollouts of a whole population: a batched policy reads the robots' sensors
every control period and sets their servo targets; physics runs in :mod:`mujoco.rollout`
threads between control steps.

Each control step ``c`` (``control_steps = k`` physics steps, e.g. 2-5 steps of 4 ms on the
NAO): the observations of every individual still running are built from its current state
(:class:`~evomotion.sim.observations.ObservationBuilder`), the policy is called once,
``policy(rows, obs[m, o]) -> actions[m, a]`` (``rows``: the individuals' indices, so the caller
picks their parameters), and the targets are held for ``k`` physics steps of all of them in
one ``mujoco.rollout`` call (persistent threads, one model per world).

- Actions are offsets (rad) from the nominal pose of the driven actuators (``columns``,
  default the robot's evolved joints); the simulator clips ``nominal + action`` to the joint
  ranges (the robot's ``[evolve]`` ranges, else the model's joint and control ranges); a NaN
  action counts as 0 (the nominal pose). Undriven actuators hold the nominal pose.
- ``followers``: (follower, leader) actuator pairs whose follower copies the leader's target
  (two actuators of one motor: the NAO's hip yaw-pitch joints).
- Latency: an individual's targets take effect ``latency_steps`` physics steps late (the
  world's servo delay, :mod:`evomotion.sim.worlds`): a FIFO of its last targets, read at
  physics-step resolution (step ``t`` uses the target sent at control step
  ``floor((t - d) / k)``; before the first one arrives the servos hold the nominal pose).
- Pushes: a world's impulse ``push_ns`` (N s) on the torso as the force ``push_ns / (dt *
  push_steps)`` (``xfrc_applied``) during ``push_steps`` physics steps from ``push_time_s``
  (``push_steps = 1``: as the open-loop worlds apply it).
- Early stop: after every control step, individuals fallen at any of its physics steps (the
  torso test of :func:`evomotion.sim.rollout.fell`) leave the batch; they are reported fallen,
  their later records repeat their last state.

Each trajectory depends only on its own world, start and policy outputs: results are
bit-identical for any thread count. Between calls MuJoCo's solver warm start is not carried
(``mujoco.rollout`` does not return it), so a run equals the open-loop rollout of the same
targets stepped in the same ``k``-step calls exactly (``BatchSimulator.run_until``,
``simulate_worlds`` with ``segment_steps = k``) and one open-loop call of the whole horizon
only closely (the NAO standing 2 s: positions within 5e-8, velocities ~2e-6).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from evomotion.errors import InputError
from evomotion.sim.closed_loop_parts import (
    PushSchedule,
    TargetFifo,
    first_fallen,
    initial_sensors,
    target_bounds,
)
from evomotion.sim.observations import ObservationBuilder, ObservationSpec
from evomotion.sim.state import QPOS_OFFSET, STATE_SPEC

#: ``policy(rows[m], obs[m, o]) -> actions[m, a]``: the batched policy of the running rows
Policy = Callable[[np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class ClosedLoopResult:
    """One closed-loop run of ``n`` individuals over ``C = ceil(nstep / k)`` control steps.

    ``torso[n, C + 1, 13]``: the torso's free-joint ``qpos`` (x, y, z, qw, qx, qy, qz) and
    ``qvel`` (world linear, body angular velocity) at the start and after each control step
    (after a fall, the last simulated state repeated); ``fell[n]``; ``fall_step[n]``: index of
    the first physics step after which the robot is fallen (``nstep`` if never);
    ``steps[n]``: physics steps simulated; ``obs_count[n]``, ``obs_sum[n, o]``,
    ``obs_sumsq[n, o]``: float64 moments of the observations each individual's policy saw,
    accumulated in control-step order (:func:`total_moments` combines them in row order);
    ``states[n, C + 1, nstate]`` and ``targets[n, C, a]`` (the clipped targets sent) when
    recorded."""

    torso: np.ndarray
    fell: np.ndarray
    fall_step: np.ndarray
    steps: np.ndarray
    obs_count: np.ndarray
    obs_sum: np.ndarray
    obs_sumsq: np.ndarray
    control_dt_s: float
    physics_dt_s: float
    states: np.ndarray | None = None
    targets: np.ndarray | None = None

    @property
    def fall_time_s(self) -> np.ndarray:
        """Time (s) from the start to the end of the first fallen physics step (``nstep *
        dt`` where the robot never fell)."""
        return (self.fall_step + self.fell) * self.physics_dt_s


def total_moments(result: ClosedLoopResult) -> tuple[int, np.ndarray, np.ndarray]:
    """(count, sum[o], sum of squares[o]) over the whole population, added in row order (the
    same for any split of the rows, e.g. over evaluators, combined in row order)."""
    return (int(result.obs_count.sum()), np.add.reduce(result.obs_sum, axis=0),
            np.add.reduce(result.obs_sumsq, axis=0))


class Configured:
    """What :func:`configure` sets on a closed-loop simulator (this one and Warp's)."""

    robot: Any
    model: mujoco.MjModel
    k: int
    push_steps: int
    observe: ObservationBuilder
    columns: np.ndarray
    nominal: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    fall_height_m: float
    fall_tilt_rad: float


class ClosedLoopSimulator(Configured):
    """Closed-loop rollouts of ``robot`` with ``nthread`` persistent ``mujoco.rollout``
    threads (see the module doc); use it as a context manager or :meth:`close` it."""

    def __init__(self, robot, observations: ObservationSpec, control_steps: int,
                 nthread: int = 1, columns: Sequence[int] | np.ndarray | None = None,
                 nominal: np.ndarray | None = None, push_steps: int = 1,
                 fall_height_m: float | None = None,
                 fall_tilt_rad: float | None = None,
                 followers: Sequence[tuple[int, int]] = ()) -> None:
        configure(self, robot, observations, control_steps, nthread, columns, nominal,
                  push_steps, fall_height_m, fall_tilt_rad)
        self.followers = _followers(followers, self.model.nu, self.columns)
        self.nthread = int(nthread)
        self.datas = [mujoco.MjData(self.model) for _ in range(self.nthread)]
        self._runner = mj_rollout.Rollout(nthread=self.nthread) if self.nthread > 1 else None
        self.nstate = int(mujoco.mj_stateSize(self.model, STATE_SPEC))
        self.dt = float(self.model.opt.timestep)
        self.steps_simulated = 0
        self.rollout_seconds = 0.0  # wall time spent inside mujoco.rollout (profiling)

    @property
    def action_size(self) -> int:
        return int(self.columns.size)

    @property
    def observation_size(self) -> int:
        return self.observe.size

    def close(self) -> None:
        if self._runner is not None:
            self._runner.close()
            self._runner = None

    def __enter__(self) -> ClosedLoopSimulator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _step(self, models: list, state: np.ndarray, ctrl: np.ndarray, spec: int,
              nstep: int) -> tuple[np.ndarray, np.ndarray]:
        m = state.shape[0]
        out = np.empty((m, nstep, self.nstate))
        sens = np.empty((m, nstep, self.model.nsensordata))
        kw = {"control_spec": spec, "nstep": nstep, "state": out, "sensordata": sens,
              "skip_checks": True}
        t0 = time.perf_counter()
        if self._runner is not None:
            self._runner.rollout(models, self.datas, state, ctrl, **kw)
        else:
            mj_rollout.rollout(models, self.datas[0], state, ctrl, **kw)
        self.rollout_seconds += time.perf_counter() - t0
        self.steps_simulated += m * nstep
        return out, sens

    def run(self, policy: Policy, worlds: Sequence | int, nstep: int, *,
            commands: np.ndarray | None = None, initial_state: np.ndarray | None = None,
            record_states: bool = False, record_targets: bool = False) -> ClosedLoopResult:
        """Run ``worlds`` (perturbed :class:`~evomotion.sim.worlds.World` s, one per
        individual, or a count ``n`` of individuals in the robot's own model) for ``nstep``
        physics steps under ``policy`` (see the module doc). ``commands[n, command_size]``
        (held for the whole run) or ``commands[n, C, command_size]`` (one per control step,
        ``C = ceil(nstep / k)``: a command schedule) feed the ``command`` channel;
        ``initial_state``: ``[nstate]`` or ``[n, nstate]``
        (default the robot's ``state0``)."""
        worlds = list(worlds) if not isinstance(worlds, int | np.integer) else int(worlds)
        n = len(worlds) if isinstance(worlds, list) else worlds
        nstep = int(nstep)
        if n < 1 or nstep < 1:
            raise InputError(f"closed loop: expected >= 1 individual and step, got {n}, {nstep}")
        models = np.empty(n, dtype=object)
        models[:] = [w.model for w in worlds] if isinstance(worlds, list) else [self.model] * n
        _check_sizes(self.model, models)
        latency = np.array([w.latency_steps for w in worlds] if isinstance(worlds, list)
                           else np.zeros(n), dtype=np.int64)
        pushes = PushSchedule.of(worlds if isinstance(worlds, list) else [], n, self.model,
                                 self.push_steps, nstep)
        spec = int(mujoco.mjtState.mjSTATE_CTRL) | (
            int(mujoco.mjtState.mjSTATE_XFRC_APPLIED) if pushes.any else 0)
        state = _rows(self.robot.state0 if initial_state is None else initial_state,
                      (n, self.nstate), "initial_state")
        sensors = (initial_sensors(self.model, state) if self.observe.needs_sensors
                   else np.zeros((n, self.model.nsensordata)))
        nctrl = math.ceil(nstep / self.k)
        cmd = None if commands is None else _schedule(commands, n, nctrl,
                                                      self.spec_command_size)
        rec = _Records(n, nctrl, self.observe.size, state, self.model.nq, self.action_size,
                       record_states, record_targets)
        fifo = TargetFifo(n, self.nominal, latency, self.k)
        alive = np.arange(n)
        model_list = models.tolist()
        for c in range(nctrl):
            t0, kk = c * self.k, min(self.k, nstep - c * self.k)
            obs = self.observe(state[alive], sensors[alive],
                               None if cmd is None else cmd[alive, c])
            rec.observed(alive, obs)
            rows = alive.view()
            rows.flags.writeable = False  # the policy reads the rows, cannot edit ours
            targets = self._targets(policy(rows, obs), alive.size)
            rec.sent(alive, c, targets)
            fifo.push(alive, c, self.full_targets(targets))
            ctrl = fifo.controls(alive, t0, kk)
            if pushes.any:
                ctrl = np.concatenate([ctrl, pushes.xfrc(alive, t0, kk)], axis=2)
            out, sens = self._step(model_list, state[alive], np.ascontiguousarray(ctrl), spec,
                                   kk)
            state[alive], sensors[alive] = out[:, -1], sens[:, -1]
            rec.stepped(alive, c + 1, out[:, -1], kk)
            fallen = first_fallen(out, self.fall_height_m, self.fall_tilt_rad)
            if (fallen < kk).any():
                gone = fallen < kk
                rec.fall(alive[gone], t0 + fallen[gone])
                alive = alive[~gone]
                model_list = models[alive].tolist()
            if alive.size == 0:
                break
        return rec.result(nstep, self.k * self.dt, self.dt)

    @property
    def spec_command_size(self) -> int:
        return int(self.observe.spec.command_size)

    def full_targets(self, targets: np.ndarray) -> np.ndarray:
        """Every actuator's target ``[..., nu]`` from the driven columns' ``targets[..., a]``:
        the nominal pose elsewhere, a follower copying its leader (one motor behind two
        actuators: the NAO's hip yaw-pitch)."""
        t = np.asarray(targets, dtype=np.float64)
        full = np.broadcast_to(self.nominal, t.shape[:-1] + (self.model.nu,)).copy()
        full[..., self.columns] = t
        if self.followers.size:
            full[..., self.followers[:, 0]] = full[..., self.followers[:, 1]]
        return full

    def _targets(self, actions: np.ndarray, m: int) -> np.ndarray:
        a = np.asarray(actions, dtype=np.float64)
        if a.shape != (m, self.columns.size):
            raise ValueError(f"closed loop: the policy returned shape {a.shape}, expected "
                             f"{(m, int(self.columns.size))}")
        a = np.where(np.isnan(a), 0.0, a)
        return np.clip(self.nominal[self.columns] + a, self.lower, self.upper)


def configure(sim: Configured, robot, observations: ObservationSpec, control_steps: int,
              nthread: int, columns: Sequence[int] | np.ndarray | None, nominal: np.ndarray | None,
              push_steps: int, fall_height_m: float | None, fall_tilt_rad: float | None) -> None:
    """The settings every closed loop (CPU, MuJoCo Warp) checks and keeps on ``sim``: the robot
    and model, ``k`` physics steps per control step, the observation builder, the driven
    columns, their nominal targets and bounds, the push length and the fall thresholds."""
    if int(control_steps) < 1 or int(push_steps) < 1 or int(nthread) < 1:
        raise InputError("closed loop: control_steps, push_steps and nthread must be >= 1, "
                         f"got {control_steps}, {push_steps}, {nthread}")
    sim.robot, sim.model = robot, robot.model
    sim.k, sim.push_steps = int(control_steps), int(push_steps)
    sim.observe = ObservationBuilder(observations, robot)
    sim.columns = np.asarray(robot.columns if columns is None else columns, np.int64)
    sim.nominal = np.array(robot.pose if nominal is None else nominal, dtype=np.float64)
    if sim.nominal.shape != (sim.model.nu,):
        raise InputError(f"closed loop: nominal must hold {sim.model.nu} targets")
    sim.lower, sim.upper = target_bounds(robot, sim.columns)
    sim.fall_height_m = robot.fall_height_m if fall_height_m is None else fall_height_m
    sim.fall_tilt_rad = robot.fall_tilt_rad if fall_tilt_rad is None else fall_tilt_rad


def _check_sizes(model: mujoco.MjModel, models: np.ndarray) -> None:
    """One :class:`InputError` unless every world's model has the robot's sizes (they run in
    one ``mujoco.rollout`` batch, whose shape checks are skipped)."""
    sizes = ("nq", "nv", "nu", "na", "nbody", "nsensordata")
    want = tuple(getattr(model, s) for s in sizes)
    for i, m in enumerate(models):  # once per run, before any physics
        if not isinstance(m, mujoco.MjModel) or tuple(getattr(m, s) for s in sizes) != want:
            raise InputError(f"closed loop: world {i}'s model is not the robot's "
                             f"(sizes {', '.join(sizes)} must be {want})")


def _followers(pairs, nu: int, columns: np.ndarray) -> np.ndarray:
    """``[k, 2]`` (follower, leader) actuator pairs: the follower's target is the leader's."""
    a = np.asarray(list(pairs), dtype=np.int64).reshape(-1, 2)
    if a.size and (((a < 0) | (a >= nu)).any() or np.isin(a[:, 0], columns).any()
                   or np.isin(a[:, 0], a[:, 1]).any()):
        raise InputError(f"closed loop: followers must be (follower, leader) actuators in "
                         f"0..{nu - 1}, a follower neither driven nor a leader, got "
                         f"{a.tolist()}")
    return a


def _schedule(commands, n: int, nctrl: int, size: int) -> np.ndarray:
    """``commands`` (``[size]``, ``[n, size]`` or a schedule ``[n, nctrl, size]``) as a
    float64 ``[n, nctrl, size]`` schedule."""
    a = np.asarray(commands, dtype=np.float64)
    if a.ndim == 3:
        if a.shape != (n, nctrl, size):
            raise InputError(f"closed loop: a command schedule must have shape "
                             f"{(n, nctrl, size)}, got {a.shape}")
        if not np.isfinite(a).all():
            raise InputError("closed loop: commands must be finite")
        return a
    return np.repeat(_rows(a, (n, size), "commands")[:, None], nctrl, axis=1)


def _rows(values, shape: tuple[int, int], name: str) -> np.ndarray:
    """``values`` (one row or one per individual) as a float64 ``[n, width]`` array."""
    a = np.asarray(values, dtype=np.float64)
    if a.ndim not in (1, 2) or a.shape[-1] != shape[1] or (a.ndim == 2
                                                           and a.shape[0] not in (1, shape[0])):
        raise InputError(f"closed loop: {name} must have shape ({shape[1]},) or {shape}, "
                         f"got {a.shape}")
    if not np.isfinite(a).all():
        raise InputError(f"closed loop: {name} must be finite")
    return np.array(np.broadcast_to(a, shape))


class _Records:
    """What a run records, per individual (see :class:`ClosedLoopResult`)."""

    def __init__(self, n: int, nctrl: int, o: int, state: np.ndarray, nq: int, a: int,
                 record_states: bool, record_targets: bool) -> None:
        self.n, self.nctrl = n, nctrl
        self._qpos = slice(QPOS_OFFSET, QPOS_OFFSET + 7)  # the free joint comes first
        self._qvel = slice(QPOS_OFFSET + nq, QPOS_OFFSET + nq + 6)
        self.torso = np.empty((n, nctrl + 1, 13))
        self.states = np.empty((n, nctrl + 1, state.shape[1])) if record_states else None
        self.targets = np.zeros((n, nctrl, a)) if record_targets else None
        self.last = np.zeros(n, dtype=np.int64)  # last control step recorded
        self.fell = np.zeros(n, dtype=bool)
        self.fall_step = np.full(n, -1, dtype=np.int64)
        self.steps = np.zeros(n, dtype=np.int64)
        self.count = np.zeros(n, dtype=np.int64)
        self.sum, self.sumsq = np.zeros((n, o)), np.zeros((n, o))
        self._record(np.arange(n), 0, state)

    def _record(self, rows: np.ndarray, c: int, state: np.ndarray) -> None:
        self.torso[rows, c, :7] = state[:, self._qpos]
        self.torso[rows, c, 7:] = state[:, self._qvel]
        if self.states is not None:
            self.states[rows, c] = state
        self.last[rows] = c

    def observed(self, rows: np.ndarray, obs: np.ndarray) -> None:
        self.count[rows] += 1
        self.sum[rows] += obs
        self.sumsq[rows] += obs * obs

    def sent(self, rows: np.ndarray, c: int, targets: np.ndarray) -> None:
        if self.targets is not None:
            self.targets[rows, c] = targets

    def stepped(self, rows: np.ndarray, c: int, state: np.ndarray, nstep: int) -> None:
        self.steps[rows] += nstep
        self._record(rows, c, state)

    def fall(self, rows: np.ndarray, step: np.ndarray) -> None:
        self.fell[rows], self.fall_step[rows] = True, step

    def result(self, nstep: int, control_dt_s: float, dt_s: float) -> ClosedLoopResult:
        idx = np.minimum(np.arange(self.nctrl + 1)[None], self.last[:, None])
        rows = np.arange(self.n)[:, None]
        states = None if self.states is None else self.states[rows, idx]
        return ClosedLoopResult(
            self.torso[rows, idx], self.fell.copy(),
            np.where(self.fell, self.fall_step, nstep), self.steps.copy(), self.count.copy(),
            self.sum.copy(), self.sumsq.copy(), float(control_dt_s), float(dt_s), states,
            self.targets)
