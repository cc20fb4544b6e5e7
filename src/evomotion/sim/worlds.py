"""Perturbed worlds for stress-testing open-loop motions of any robot (domain randomisation).

A :class:`World` is an edited copy of a robot's :class:`mujoco.MjModel` plus a servo latency and
a push. :func:`make_world` applies fixed values, :func:`draw_worlds` draws ``k`` worlds from
the :class:`Perturbation` ranges with a :class:`numpy.random.Generator` (same generator state,
same worlds), and :func:`simulate_worlds` rolls them all out in one :mod:`mujoco.rollout` batch
(one model per initial state; nothing per physics step in Python).

What is edited, per world (compiled-model arrays; ``mj_setConst`` then recomputes the derived
constants such as ``body_subtreemass``):

- friction: every geom's friction coefficients (``geom_friction``, sliding, torsional and
  rolling) times one scale. MuJoCo combines two geoms' friction with the maximum (equal
  priorities), so the sole/floor contact friction is scaled by exactly that factor;
- mass: each link's ``body_mass`` and ``body_inertia`` times its own scale (the same geometry
  with another density); the torso's centre of mass ``body_ipos`` shifted by an offset (m);
- motor strength: each position actuator's ``kp`` (``actuator_gainprm[:, 0]`` and
  ``-actuator_biasprm[:, 1]``) and its ``actuator_forcerange`` times its own scale;
- latency: the control sequence delayed by ``latency_steps`` physics steps (the first target is
  held meanwhile): the servo acts on the target sent ``latency_steps * dt`` s earlier;
- push: an impulse ``push_ns`` (N·s, world frame) given to the torso at ``push_time_s``, as
  the force ``push_ns / dt`` on the torso's centre of mass (``xfrc_applied``) during the one
  physics step starting then: the robot's linear momentum changes by ``push_ns``, i.e. its
  velocity by ``push_ns / total mass`` (0.47 m/s for 2.5 N·s on the 5.3 kg NAO). The
  default push range is the NAO's (:data:`PUSH_REFERENCE_MASS_KG`); another robot's is scaled
  by its own mass (:meth:`Perturbation.for_mass`): the same change of velocity.

Default ranges (U uniform, x scale; sources in ``/work/shared/reference/walking.md`` §5, the
NAO in ``nao-h25.md``) are documented per field of :class:`Perturbation`.
"""

from __future__ import annotations

import copy
import dataclasses
import os
from dataclasses import dataclass, field

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from evomotion.core.problem import Evaluation
from evomotion.errors import InputError
from evomotion.sim.rollout import rollout_segments
from evomotion.sim.state import STATE_SPEC

#: the mass the default push range was set for (kg): the NAO's published total mass
PUSH_REFERENCE_MASS_KG = 5.3054
TORSO = "torso"  # the NAO's body with the free joint: CoM offsets and pushes act on it


def torso_id(model: mujoco.MjModel) -> int:
    """The body CoM offsets and pushes act on: the one carrying the model's first joint when
    that is a free joint (the NAO's ``torso``, any robot of :mod:`evomotion.sim.robots`), else
    the body named :data:`TORSO`."""
    if model.njnt and model.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE:
        return int(model.jnt_bodyid[0])
    return int(model.body(TORSO).id)


def _check_range(name: str, lo_hi: tuple[float, float], low: float, low_ok: bool) -> None:
    lo, hi = (float(v) for v in lo_hi)
    if not (np.isfinite(lo) and np.isfinite(hi)) or lo > hi:
        raise InputError(f"{name}: expected a finite range lo <= hi, got {lo_hi}")
    if lo < low or (lo == low and not low_ok):
        raise InputError(f"{name}: expected values {'>=' if low_ok else '>'} {low}, got {lo}")


@dataclass(frozen=True)
class Perturbation:
    """Ranges of the perturbations, drawn uniformly (``(lo, hi)``; ``lo == hi`` pins a value).

    Scales are dimensionless factors of the model's nominal values; the NAO model's floor and
    sole friction is 0.7.
    """

    #: friction scale, x U(0.5, 1.4): the model's 0.7 becomes 0.35..0.98, about Playground
    #: G1's mu U(0.4, 1) [S1] and inside the wider T1 ranges U(0.2, 0.6) [S1] / U(0.1, 2) [S2].
    friction_scale: tuple[float, float] = (0.5, 1.4)
    #: link mass (and inertia) scale, per link, x U(0.9, 1.1): Playground G1 [S1]; between
    #: T1's x U(0.98, 1.02) [S1] and H1's x U(0.7, 1.3) [S4].
    mass_scale: tuple[float, float] = (0.9, 1.1)
    #: torso CoM offset (m), per axis U(-0.02, 0.02): the base CoM +-0.1 m of T1 [S2] and H1
    #: [S4] (1.2-1.8 m tall robots) scaled to the 0.57 m NAO (~+-0.03 m), rounded down.
    com_offset_m: tuple[float, float] = (-0.02, 0.02)
    #: motor strength scale (kp and force range), per actuator, x U(0.9, 1.1): T1's kp
    #: x U(0.9, 1.1) [S1]; booster_gym x U(0.95, 1.05) [S2], H1 x U(0.75, 1.25) [S4].
    motor_scale: tuple[float, float] = (0.9, 1.1)
    #: servo latency in physics steps (4 ms each), integer U{0..10} = 0-40 ms: H1 uses 1-3
    #: control steps = 20-60 ms [S4]; NAO's DCM runs a 10 ms cycle, so 0-4 cycles.
    latency_steps: tuple[int, int] = (0, 10)
    #: lateral push impulse (N s, along +y: to the robot's left), U(-2.5, 2.5): at most
    #: 2.5 N s on 5.3 kg = 0.47 m/s, H1's push <= 0.5 m/s [S4] (velocity pushes carry over
    #: across robot sizes, walking.md §5 last line); T1 pushes 0.1-1 m/s [S1].
    push_ns: tuple[float, float] = (-2.5, 2.5)
    #: push time as a fraction of the motion's duration, U(0.25, 0.75) (one push per run; the
    #: sources push every 5-10 s, longer than a motion).
    push_at: tuple[float, float] = (0.25, 0.75)

    def validate(self) -> None:
        """One-line :class:`InputError` for a bad range."""
        _check_range("friction_scale", self.friction_scale, 0.0, False)
        _check_range("mass_scale", self.mass_scale, 0.0, False)
        _check_range("com_offset_m", self.com_offset_m, -np.inf, True)
        _check_range("motor_scale", self.motor_scale, 0.0, False)
        _check_range("latency_steps", self.latency_steps, 0, True)
        if any(int(v) != v for v in self.latency_steps):
            raise InputError(f"latency_steps: expected integers, got {self.latency_steps}")
        _check_range("push_ns", self.push_ns, -np.inf, True)
        _check_range("push_at", self.push_at, 0.0, True)
        if self.push_at[1] > 1.0:
            raise InputError(f"push_at: expected fractions in [0, 1], got {self.push_at}")

    def for_mass(self, mass_kg: float) -> Perturbation:
        """These ranges for a robot of ``mass_kg``: the push impulses scaled by ``mass_kg /``
        :data:`PUSH_REFERENCE_MASS_KG` (the same change of velocity; unchanged for the NAO)."""
        if mass_kg == PUSH_REFERENCE_MASS_KG:
            return self
        lo, hi = (v * mass_kg / PUSH_REFERENCE_MASS_KG for v in self.push_ns)
        return dataclasses.replace(self, push_ns=(lo, hi))


@dataclass(frozen=True)
class World:
    """One perturbed world: the edited model, the servo delay and the push."""

    model: mujoco.MjModel
    latency_steps: int = 0
    push_ns: tuple[float, float, float] = (0.0, 0.0, 0.0)  # impulse on the torso, world frame
    push_time_s: float = 0.0
    params: dict = field(default_factory=dict)  # the drawn values, for reports


def make_world(base: mujoco.MjModel, *, friction_scale: float = 1.0,
               mass_scale: float | np.ndarray = 1.0,
               com_offset_m: tuple[float, float, float] | np.ndarray = (0.0, 0.0, 0.0),
               motor_scale: float | np.ndarray = 1.0, latency_steps: int = 0,
               push_ns: tuple[float, float, float] | np.ndarray = (0.0, 0.0, 0.0),
               push_time_s: float = 0.0) -> World:
    """A copy of ``base`` with the given perturbations (``mass_scale``: one value or one per
    body after the world body; ``motor_scale``: one value or one per actuator)."""
    m = copy.copy(base)
    m.geom_friction[:] = base.geom_friction * float(friction_scale)
    scale = np.ones(base.nbody)
    scale[1:] = np.broadcast_to(np.asarray(mass_scale, float), (base.nbody - 1,))
    m.body_mass[:] = base.body_mass * scale
    m.body_inertia[:] = base.body_inertia * scale[:, None]
    m.body_ipos[torso_id(m)] = base.body_ipos[torso_id(base)] + np.asarray(com_offset_m)
    ms = np.broadcast_to(np.asarray(motor_scale, float), (base.nu,))
    m.actuator_gainprm[:, 0] = base.actuator_gainprm[:, 0] * ms
    m.actuator_biasprm[:, 1] = base.actuator_biasprm[:, 1] * ms
    m.actuator_forcerange[:] = base.actuator_forcerange * ms[:, None]
    mujoco.mj_setConst(m, mujoco.MjData(m))
    params = {"friction_scale": float(friction_scale),
              "mass_scale_mean": float(scale[1:].mean()),
              "com_offset_m": [float(v) for v in np.asarray(com_offset_m)],
              "motor_scale_mean": float(ms.mean()), "latency_steps": int(latency_steps),
              "push_ns": [float(v) for v in np.asarray(push_ns)],
              "push_time_s": float(push_time_s)}
    px, py, pz = (float(v) for v in np.asarray(push_ns))
    return World(m, int(latency_steps), (px, py, pz), float(push_time_s), params)


def _latin(rng: np.random.Generator, lo: float, hi: float, k: int, cols: int = 0) -> np.ndarray:
    """``k`` draws (``[k]``, or ``[k, cols]`` with each column its own design) of a Latin
    hypercube on ``[lo, hi]``: one draw in each of ``k`` equal strata, in random order."""
    shape = (k, cols) if cols else (k,)
    strata = np.argsort(rng.random(shape), axis=0)
    return lo + (hi - lo) * (strata + rng.random(shape)) / k


def draw_worlds(base: mujoco.MjModel, perturbation: Perturbation, k: int,
                rng: np.random.Generator, duration_s: float,
                design: str = "random") -> list[World]:
    """``k`` worlds drawn from ``perturbation``'s ranges; pushes at a fraction ``push_at`` of
    ``duration_s`` (s). Deterministic in ``rng``'s state; every range is drawn (pinned ones
    too), so pinning one range does not change the others' draws.

    ``design = "latin"`` draws every range as a Latin hypercube instead of independently:
    each of the ``k`` equal strata of each range holds one world (the latency rounded to its
    integers), so a few worlds still cover the extremes (training with few worlds)."""
    perturbation.validate()
    p = perturbation
    if design not in ("random", "latin"):
        raise InputError(f"draw_worlds: design must be 'random' or 'latin', got {design!r}")
    if design == "latin":
        friction = _latin(rng, *p.friction_scale, k)
        mass = _latin(rng, *p.mass_scale, k, base.nbody - 1)
        com = _latin(rng, *p.com_offset_m, k, 3)
        motor = _latin(rng, *p.motor_scale, k, base.nu)
        lat_lo, lat_hi = (int(v) for v in p.latency_steps)
        latency = np.minimum(np.floor(_latin(rng, lat_lo, lat_hi + 1, k)), lat_hi).astype(int)
        push = _latin(rng, *p.push_ns, k)
        when = _latin(rng, *p.push_at, k) * float(duration_s)
    else:
        friction = rng.uniform(*p.friction_scale, size=k)
        mass = rng.uniform(*p.mass_scale, size=(k, base.nbody - 1))
        com = rng.uniform(*p.com_offset_m, size=(k, 3))
        motor = rng.uniform(*p.motor_scale, size=(k, base.nu))
        latency = rng.integers(int(p.latency_steps[0]), int(p.latency_steps[1]) + 1, size=k)
        push = rng.uniform(*p.push_ns, size=k)
        when = rng.uniform(*p.push_at, size=k) * float(duration_s)
    return [make_world(base, friction_scale=friction[i], mass_scale=mass[i],
                       com_offset_m=com[i], motor_scale=motor[i],
                       latency_steps=int(latency[i]), push_ns=(0.0, push[i], 0.0),
                       push_time_s=when[i]) for i in range(k)]


def delayed_controls(controls: np.ndarray, latency_steps: np.ndarray) -> np.ndarray:
    """``controls[nstep, nu]`` or ``[k, nstep, nu]`` delayed per world: ``out[w, t] =
    controls[w, max(t - latency_steps[w], 0)]`` (``[k, nstep, nu]``)."""
    lat = np.asarray(latency_steps, dtype=np.int64)
    ctrl = np.broadcast_to(controls, (lat.size, *np.shape(controls)[-2:]))
    idx = np.maximum(np.arange(ctrl.shape[1])[None, :] - lat[:, None], 0)
    return np.take_along_axis(ctrl, idx[:, :, None], axis=1)


def _pushes(worlds: list[World], nstep: int) -> tuple[np.ndarray, np.ndarray]:
    """(``impulse[k, 3]`` N s, ``step[k]``) of each world's push; ``step`` is ``-1`` where a
    world has no push before the last step."""
    dt = float(worlds[0].model.opt.timestep)
    push = np.array([w.push_ns for w in worlds], dtype=float)
    step = np.array([int(round(w.push_time_s / dt)) for w in worlds])
    return push, np.where(push.any(axis=1) & (step < nstep), step, -1)


def _segment_controls(c: np.ndarray, push: np.ndarray, step: np.ndarray, rows: np.ndarray,
                      start: int, stop: int, base: mujoco.MjModel,
                      pushed: bool) -> tuple[np.ndarray, int]:
    """The controls ``c`` of ``rows`` for steps ``start:stop`` with their ``control_spec``.
    When any world of the batch is ``pushed``, every segment carries ``xfrc_applied`` columns
    (zero but at a push), so no force is left over in a thread's ``MjData`` and a trajectory
    does not depend on the other trajectories of its batch."""
    if not pushed:
        return np.ascontiguousarray(c, dtype=np.float64), int(mujoco.mjtState.mjSTATE_CTRL)
    spec = int(mujoco.mjtState.mjSTATE_CTRL) | int(mujoco.mjtState.mjSTATE_XFRC_APPLIED)
    xfrc = np.zeros((len(rows), stop - start, base.nbody, 6))
    hit = np.flatnonzero((step[rows] >= start) & (step[rows] < stop))
    dt = float(base.opt.timestep)
    xfrc[hit, step[rows[hit]] - start, torso_id(base), :3] = push[rows[hit]] / dt
    c = np.concatenate([c, xfrc.reshape(len(rows), stop - start, -1)], axis=2)
    return np.ascontiguousarray(c, dtype=np.float64), spec


def aggregate_worlds(ev: Evaluation, n: int, k: int, aggregate: str = "mean",
                     quantile: float = 0.25) -> Evaluation:
    """The evaluation of ``n`` genomes from that of their ``n * k`` world rollouts (genome-
    major: row ``i * k + w``): fitness the mean (``aggregate = "mean"``) or the ``quantile``
    of each genome's K values, every metric its mean over the K worlds (a 0/1 ``fell`` becomes
    the share of worlds fallen)."""
    fit = ev.fitness.reshape(n, k)
    agg = fit.mean(axis=1) if aggregate == "mean" else np.quantile(fit, quantile, axis=1)
    metrics = {m: np.asarray(v, float).reshape(n, k).mean(axis=1)
               for m, v in ev.metrics.items()}
    return Evaluation(agg, metrics)


def simulate_worlds(worlds: list[World], initial_state: np.ndarray, controls: np.ndarray,
                    nthread: int = 1, sensors: bool = False, stopped=None,
                    segment_steps: int = 0, simulator=None, feedback=None,
                    control_steps: int = 0) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Roll out every world from ``initial_state`` (``[nstate]`` or ``[k, nstate]``,
    ``STATE_SPEC``) under ``controls`` (``[nstep, nu]`` or ``[k, nstep, nu]``), delayed and
    pushed per world, in one ``mujoco.rollout`` batch with ``nthread`` threads (0: all cores).
    Returns ``states[k, nstep, nstate]`` (with ``sensors``: also ``sensordata[k, nstep, n]``).
    A push at or after the last step is not applied.

    With ``stopped(states_segment) -> bool[k]`` and ``segment_steps``, the batch is stepped in
    segments of ``segment_steps`` (at the same steps for every trajectory, whatever the batch
    holds) and worlds for which ``stopped`` is true after a segment are not simulated further
    (their remaining rows repeat their last state), as :meth:`~evomotion.sim.rollout.
    BatchSimulator.run_until` does for one model. A trajectory's states depend only on its own
    world, start and controls, so any split of the worlds over batches (evaluators) gives the
    same states.

    With a :class:`~evomotion.sim.warp_rollout.WarpSimulator` as ``simulator`` the batch runs
    on MuJoCo Warp instead (:mod:`evomotion.sim.warp_worlds`); ``nthread`` is then unused.

    With ``feedback(rows, start, states) -> delta[len(rows), nu]`` (a controller reading the
    state of trajectories ``rows`` at step ``start``) the batch is stepped ``control_steps``
    at a time; each period's targets are ``controls`` plus the feedback read at its start, and
    reach the servos after each world's latency like the rest (the CPU only; the early stop
    is then checked every control period)."""
    if not worlds:
        raise InputError("simulate_worlds: expected at least one world")
    k, base = len(worlds), worlds[0].model
    lat = np.array([w.latency_steps for w in worlds], dtype=np.int64)
    if feedback is None:
        ctrl = delayed_controls(controls, lat)
    else:
        if getattr(simulator, "backend", "cpu") == "warp" or control_steps < 1:
            raise InputError("simulate_worlds: feedback runs on the CPU, every control_steps "
                             ">= 1 physics steps")
        ctrl = np.array(np.broadcast_to(controls, (k, *np.shape(controls)[-2:])), float)
        segment_steps = int(control_steps)  # rollout_segments steps a stop rule's segments
        if stopped is None:
            stopped = lambda s: np.zeros(len(s), bool)  # noqa: E731 - never stops
    nstep = ctrl.shape[1]
    push, step = _pushes(worlds, nstep)
    nstate = mujoco.mj_stateSize(base, STATE_SPEC)
    models = [w.model for w in worlds]
    if getattr(simulator, "backend", "cpu") == "warp":
        from evomotion.sim.warp_worlds import simulate_worlds_warp

        impulse = push * (step >= 0)[:, None]
        out = simulate_worlds_warp(simulator, models, np.broadcast_to(initial_state, (k, nstate)),
                                   ctrl, impulse, step, torso_id(base), stopped,
                                   segment_steps)
        return out if sensors else out[0]
    nthread = int(nthread) if nthread and nthread > 0 else (os.cpu_count() or 1)
    nthread = max(1, min(nthread, k))
    pushed = bool((step >= 0).any())
    runner = mj_rollout.Rollout(nthread=nthread) if nthread > 1 else None
    datas = [mujoco.MjData(base) for _ in range(nthread)]

    def segment(rows: np.ndarray, start: int, stop: int, init: np.ndarray) -> np.ndarray:
        if feedback is None:
            return ctrl[rows, start:stop]
        ctrl[rows, start:stop] += np.asarray(feedback(rows, start, init))[:, None, :]
        sent = np.maximum(np.arange(start, stop)[None, :] - lat[rows][:, None], 0)
        return ctrl[rows[:, None], sent]  # what the servos act on: sent latency steps ago

    def roll(rows: np.ndarray, start: int, stop: int, init: np.ndarray):
        c, spec = _segment_controls(segment(rows, start, stop, init), push, step, rows, start,
                                    stop, base, pushed)
        args = ([models[i] for i in rows], datas if runner else datas[0], init, c)
        kw = {"control_spec": spec, "nstep": stop - start}
        return runner.rollout(*args, **kw) if runner else mj_rollout.rollout(*args, **kw)

    try:
        states, sens = rollout_segments(roll, np.broadcast_to(initial_state, (k, nstate)),
                                        nstep, base.nsensordata, stopped, segment_steps)
    finally:
        if runner is not None:
            runner.close()
    return (states, sens) if sensors else states
