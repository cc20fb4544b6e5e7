"""Execute a paper-003 walking plan on the MuJoCo quadruped and measure what happens.

The joint targets of :mod:`.trajectory` are precomputed and simulated open loop with
``mujoco.rollout`` (chunks of ``CHUNK_STEPS`` steps). From the recorded states and contact
sensors (per foot: the floor's net force on it and its position; the torso's floor contact):
torso height and tilt, torso-floor contact, the support margin of :mod:`.support` (centre of
pressure of the feet's normal forces against the hull of the feet in contact; a foot counts
as in contact above ``CONTACT_FRACTION`` of the robot's weight), and the final torso pose
against the plan's last body pose. Units: m, rad, s, N. Non-finite input or an unstable
simulation is reported (``diverged``), never raised; an execution longer than
``MAX_SECONDS`` (computed from the plan before anything is built) is a ValueError.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from evomotion.sim.quadruped.model import FOOT_SENSOR_DIM, QuadrupedSpec, build_model
from evomotion.sim.quadruped.support import support_margins
from evomotion.sim.quadruped.trajectory import (
    build_timeline,
    initial_qpos,
    plan_arrays,
    plan_seconds,
    wrap,
)
from evomotion.sim.state import STATE_SPEC

BODY_UP_FRACTION = 0.75  # body_up needs the torso centre above this part of body_height_m
CONTACT_FRACTION = 0.01  # a foot carrying less than 1 % of the weight is not in contact
CHUNK_STEPS = 20_000
#: the longest execution simulated [s]: 600,000 steps of 2 ms, ~0.4 GB of recorded states
MAX_SECONDS = 1200.0
# defaults of execute_plan (see the package docstring for why)
LEG_SECONDS = 0.6
METRES_PER_SECOND = 0.05
RADIANS_PER_SECOND = 0.5
LIFT_M = 0.012
SETTLE_SECONDS = 0.5
FINAL_SECONDS = 0.5
_Q0 = 1  # the state vector starts with time, then qpos


@dataclass
class ExecutionResult:
    """What the simulated robot did; margins NaN where never >= 3 feet were in contact.

    ``transition_margins_m[t]``: least support margin while executing transition ``t``
    (state ``t`` to ``t + 1``); ``swing_margin_m``: the least while a foot swings;
    ``under_three_feet_s``: time with fewer than 3 feet in contact; ``fall_time_s`` /
    ``fall_transition``: when / in which transition (-1: the settle) ``body_up`` first
    failed (None while up)."""

    body_up: bool
    body_floor_contact: bool
    min_body_height_m: float
    max_tilt_rad: float
    min_support_margin_m: float
    final_position_error_m: float
    final_heading_error_rad: float
    duration_s: float
    steps: int
    diverged: bool
    swing_margin_m: float = math.nan
    under_three_feet_s: float = math.nan
    fall_time_s: float | None = None
    fall_transition: int | None = None
    wall_seconds: float = 0.0
    message: str = ""
    transition_margins_m: list[float] = field(default_factory=list)

    def to_dict(self) -> dict:
        """JSON-ready: NaN and infinities become None."""
        def clean(v: object) -> object:
            if isinstance(v, float) and not math.isfinite(v):
                return None
            if isinstance(v, list):
                return [clean(x) for x in v]
            return v
        return {k: clean(v) for k, v in asdict(self).items()}


def _failed(message: str, steps: int = 0, duration: float = 0.0,
            wall: float = 0.0) -> ExecutionResult:
    nan = math.nan
    return ExecutionResult(False, False, nan, nan, nan, nan, nan, duration, steps, True,
                           wall_seconds=wall, message=message)


def _simulate(model: mujoco.MjModel, qpos0: np.ndarray, ctrl: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, bool]:
    """``(qpos[T, nq], sensordata[T, ns], diverged)``; stops at the first bad chunk."""
    data = mujoco.MjData(model)
    data.qpos[:] = qpos0
    data.ctrl[:] = ctrl[0]
    mujoco.mj_forward(model, data)
    state = np.empty(mujoco.mj_stateSize(model, STATE_SPEC))
    mujoco.mj_getState(model, data, state, STATE_SPEC)
    qs, ss = [], []
    for start in range(0, len(ctrl), CHUNK_STEPS):
        chunk = np.ascontiguousarray(ctrl[None, start:start + CHUNK_STEPS])
        st, sd = mj_rollout.rollout(model, data, state[None], chunk)
        st, sd = st[0], sd[0]
        times = st[:, 0]
        bad = (not np.isfinite(st).all() or not np.isfinite(sd).all()
               or np.any(np.diff(times) <= 0) or times[0] <= state[0]
               or data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0)
        qs.append(st[:, _Q0:_Q0 + model.nq])
        ss.append(sd)
        if bad:
            return np.concatenate(qs), np.concatenate(ss), True
        state = st[-1]
    return np.concatenate(qs), np.concatenate(ss), False


def _analyse(spec: QuadrupedSpec, model: mujoco.MjModel, qpos: np.ndarray, sens: np.ndarray,
             transition: np.ndarray, swing: np.ndarray, goal: np.ndarray, n_trans: int
             ) -> ExecutionResult:
    dt = model.opt.timestep
    feet = sens[:, :4 * FOOT_SENSOR_DIM].reshape(len(sens), 4, FOOT_SENSOR_DIM)
    force = np.where(feet[:, :, 0] > 0, feet[:, :, 3], 0.0)
    weight = spec.total_mass_kg * -model.opt.gravity[2]
    margin, _ = support_margins(feet[:, :, 4:6], force, CONTACT_FRACTION * weight)
    touching = sens[:, 4 * FOOT_SENSOR_DIM] > 0
    z = qpos[:, 2]
    down = touching | (z < BODY_UP_FRACTION * spec.body_height_m)
    first = int(np.argmax(down)) if down.any() else None
    qx, qy = qpos[:, 4], qpos[:, 5]
    tilt = np.arccos(np.clip(1.0 - 2.0 * (qx * qx + qy * qy), -1.0, 1.0))
    w, qz = qpos[-1, 3], qpos[-1, 6]
    xx, yx = 1 - 2 * (qy[-1] ** 2 + qz ** 2), 2 * (qx[-1] * qy[-1] + w * qz)
    heading = math.atan2(yx, xx)

    def least(mask: np.ndarray) -> float:
        vals = margin[mask & np.isfinite(margin)]
        return float(vals.min()) if vals.size else math.nan

    per = [least(transition[:len(margin)] == t) for t in range(n_trans)]
    return ExecutionResult(
        body_up=first is None, body_floor_contact=bool(touching.any()),
        min_body_height_m=float(z.min()),
        max_tilt_rad=float(tilt.max()), min_support_margin_m=least(np.ones(len(margin), bool)),
        final_position_error_m=float(np.hypot(*(qpos[-1, :2] - goal[:2]))),
        final_heading_error_rad=float(abs(wrap(heading - goal[2]))),
        duration_s=len(qpos) * dt, steps=len(qpos), diverged=False,
        swing_margin_m=least(swing[:len(margin)]),
        under_three_feet_s=float(((force > CONTACT_FRACTION * weight).sum(1) < 3).sum() * dt),
        fall_time_s=None if first is None else (first + 1) * dt,
        fall_transition=None if first is None else int(transition[first]),
        transition_margins_m=per)


def simulate_plan(states: list[dict], spec: QuadrupedSpec = QuadrupedSpec(), *,
                  leg_seconds: float = LEG_SECONDS,
                  metres_per_second: float = METRES_PER_SECOND,
                  radians_per_second: float = RADIANS_PER_SECOND,
                  lift_m: float = LIFT_M, settle_seconds: float = SETTLE_SECONDS,
                  final_seconds: float = FINAL_SECONDS, record_qpos: bool = False
                  ) -> tuple[ExecutionResult, np.ndarray | None]:
    """:func:`execute_plan`, also returning ``qpos[T, nq]`` (one row per step of
    ``spec.timestep``, up to the first unstable chunk) when ``record_qpos``."""
    t0 = time.perf_counter()
    if not states:
        raise ValueError("a plan needs at least one state")
    if not (leg_seconds > 0 and metres_per_second > 0 and radians_per_second > 0
            and 0 <= lift_m <= spec.max_lift_m and settle_seconds >= 0 and final_seconds >= 0):
        raise ValueError("need positive leg_seconds and speeds, 0 <= lift_m <= "
                         f"spec.max_lift_m ({spec.max_lift_m} m), non-negative settle/final")
    body, feet = plan_arrays(states)
    if not (np.isfinite(body).all() and np.isfinite(feet).all()):
        return _failed("non-finite plan state", wall=time.perf_counter() - t0), None
    secs = plan_seconds(spec, states, leg_seconds=leg_seconds,
                        metres_per_second=metres_per_second,
                        radians_per_second=radians_per_second, settle_seconds=settle_seconds,
                        final_seconds=final_seconds)
    if secs > MAX_SECONDS:
        raise ValueError(f"the plan's execution would last {secs:.4g} simulated seconds "
                         f"(at most {MAX_SECONDS:g})")
    tl = build_timeline(spec, states, leg_seconds=leg_seconds,
                        metres_per_second=metres_per_second,
                        radians_per_second=radians_per_second, lift_m=lift_m,
                        settle_seconds=settle_seconds, final_seconds=final_seconds)
    model = build_model(spec)
    qpos0 = initial_qpos(spec, states, model.nq)
    if not (np.isfinite(tl.q).all() and np.isfinite(qpos0).all()):
        return _failed("non-finite joint targets", wall=time.perf_counter() - t0), None
    qpos, sens, diverged = _simulate(model, qpos0, tl.q)
    goal = body[-1] * [spec.unit_m, spec.unit_m, 1.0]
    if diverged:
        res = _failed("simulation unstable (non-finite state or reset)", len(qpos),
                      len(qpos) * spec.timestep)
    else:
        res = _analyse(spec, model, qpos, sens, tl.transition, tl.swing, goal,
                       len(states) - 1)
    res.wall_seconds = time.perf_counter() - t0
    return res, (qpos if record_qpos else None)


def execute_plan(states: list[dict], spec: QuadrupedSpec = QuadrupedSpec(), *,
                 leg_seconds: float = LEG_SECONDS,
                 metres_per_second: float = METRES_PER_SECOND,
                 radians_per_second: float = RADIANS_PER_SECOND,
                 lift_m: float = LIFT_M, settle_seconds: float = SETTLE_SECONDS,
                 final_seconds: float = FINAL_SECONDS) -> ExecutionResult:
    """Simulate ``states`` (plan.json ``states``: body ``[x, y, phi]`` and world feet in paper
    units) quasi-statically: a settle of ``settle_seconds`` [s], each foot swing in
    ``leg_seconds`` [s] with a ``lift_m`` [m] lift, body moves at ``metres_per_second`` and
    ``radians_per_second``, a final hold of ``final_seconds`` [s]."""
    return simulate_plan(states, spec, leg_seconds=leg_seconds,
                         metres_per_second=metres_per_second,
                         radians_per_second=radians_per_second, lift_m=lift_m,
                         settle_seconds=settle_seconds, final_seconds=final_seconds)[0]


def plan_qpos(states: list[dict], spec: QuadrupedSpec = QuadrupedSpec(),
              **kwargs: float) -> tuple[np.ndarray, float]:
    """``(qpos[T, nq], dt)`` of the simulated execution (for :func:`render_plan_video`);
    keyword arguments as :func:`execute_plan`. No rows if the plan is not finite."""
    _, qpos = simulate_plan(states, spec, record_qpos=True, **kwargs)
    return (qpos if qpos is not None else np.zeros((0, 19))), spec.timestep
