"""Warp kernels of the closed loop on MuJoCo Warp (:mod:`evomotion.sim.warp_closed_loop`).

A control step of the batch is ``observe`` (the observation vector of every world, one column
per thread, from ``qpos``, ``qvel``, ``sensordata``, the time and the commands, as
:class:`~evomotion.sim.observations.ObservationBuilder` builds it on the host), ``moments``
(float64 sums of the observations of the worlds still running), the policy (on the device:
:mod:`evomotion.sim.warp_policy`; else on the host), ``targets`` (``clip(nominal + action)``
into the latency ring), then ``k`` physics steps of ``load_ctrl`` (the delayed target),
``push``, :func:`mujoco_warp.step`, ``fall`` and ``peak``, and finally ``record``. The clock
(``clock[0]`` physics step, ``clock[1]`` control step) lives on the device, so a captured CUDA
graph replays whole control periods. Imported only with ``problem.backend = "warp"``.
"""

from __future__ import annotations

import warp as wp

# observation column kinds (``kind[j]``, with ``index[j]``)
QPOS, QVEL, GRAVITY, ROLL_PITCH, TORSO_VEL, CONTACT, PHASE, COMMAND = range(8)


@wp.func
def _third_row(qw: float, qx: float, qy: float, qz: float) -> wp.vec3:
    """Third row of the rotation matrix of a unit quaternion: ``R^T e_z``."""
    return wp.vec3(2.0 * (qx * qz - qw * qy), 2.0 * (qy * qz + qw * qx),
                   1.0 - 2.0 * (qx * qx + qy * qy))


@wp.kernel
def observe(qpos: wp.array2d(dtype=float), qvel: wp.array2d(dtype=float),
            time: wp.array(dtype=float), sensordata: wp.array2d(dtype=float),
            commands: wp.array2d(dtype=float), kind: wp.array(dtype=int),
            index: wp.array(dtype=int), free_q: int, free_v: int, omega: float,
            obs: wp.array2d(dtype=float)):
    """``obs[w, j]``: column ``j`` of kind ``kind[j]`` (``omega = 2 pi / period``)."""
    w, j = wp.tid()
    i = index[j]
    kd = kind[j]
    qw = qpos[w, free_q + 3]
    qx = qpos[w, free_q + 4]
    qy = qpos[w, free_q + 5]
    qz = qpos[w, free_q + 6]
    v = float(0.0)  # noqa: UP018 (a Warp variable, not a constant)
    if kd == QPOS:
        v = qpos[w, i]
    elif kd == QVEL:
        v = qvel[w, i]
    elif kd == GRAVITY:
        v = -_third_row(qw, qx, qy, qz)[i]
    elif kd == ROLL_PITCH:
        r3 = _third_row(qw, qx, qy, qz)
        if i == 0:  # noqa: SIM108 (Warp kernels branch, they do not select)
            v = wp.atan2(r3[1], r3[2])
        else:
            v = wp.asin(wp.clamp(-r3[0], -1.0, 1.0))
    elif kd == TORSO_VEL:  # R^T v: the conjugate quaternion's rotation
        lin = wp.vec3(qvel[w, free_v], qvel[w, free_v + 1], qvel[w, free_v + 2])
        v = wp.quat_rotate_inv(wp.quat(qx, qy, qz, qw), lin)[i]
    elif kd == CONTACT:
        if sensordata[w, i] > 0.0:
            v = 1.0
    elif kd == PHASE:
        if i == 0:  # noqa: SIM108
            v = wp.sin(omega * time[w])
        else:
            v = wp.cos(omega * time[w])
    else:
        v = commands[w, i]
    obs[w, j] = v


@wp.kernel
def moments(obs: wp.array2d(dtype=float), done: wp.array(dtype=int),
            total: wp.array2d(dtype=wp.float64), total_sq: wp.array2d(dtype=wp.float64)):
    """float64 sums of the observations of the running worlds, in control-step order."""
    w, j = wp.tid()
    if done[w] == 0:
        x = wp.float64(obs[w, j])
        total[w, j] = total[w, j] + x
        total_sq[w, j] = total_sq[w, j] + x * x


@wp.kernel
def targets(actions: wp.array2d(dtype=float), columns: wp.array(dtype=int),
            nominal: wp.array(dtype=float), lower: wp.array(dtype=float),
            upper: wp.array(dtype=float), clock: wp.array(dtype=int), depth: int,
            record: int, done: wp.array(dtype=int), ring: wp.array3d(dtype=float),
            sent: wp.array3d(dtype=float)):
    """``ring[w, c % depth, columns[j]] = clip(nominal + action, lower, upper)`` (NaN: 0)."""
    w, j = wp.tid()
    a = actions[w, j]
    if wp.isnan(a):
        a = 0.0
    col = columns[j]
    t = wp.clamp(nominal[col] + a, lower[j], upper[j])
    c = clock[1]
    ring[w, c % depth, col] = t
    if record != 0 and done[w] == 0:
        sent[w, c, j] = t


@wp.kernel
def load_ctrl(ring: wp.array3d(dtype=float), latency: wp.array(dtype=int),
              clock: wp.array(dtype=int), k: int, depth: int, nominal: wp.array(dtype=float),
              ctrl: wp.array2d(dtype=float)):
    """Physics step ``t`` uses the target sent at control step ``(t - d) // k``, the nominal
    pose before the first one arrives (``t < d``)."""
    w, j = wp.tid()
    src = clock[0] - latency[w]
    if src < 0:
        ctrl[w, j] = nominal[j]
    else:
        ctrl[w, j] = ring[w, (src // k) % depth, j]


@wp.kernel
def push(clock: wp.array(dtype=int), start: wp.array(dtype=int), steps: int,
         force: wp.array(dtype=wp.vec3), body: int,
         xfrc: wp.array2d(dtype=wp.spatial_vector)):
    """The torso force ``force[w]`` (N) during physics steps ``start .. start + steps - 1``."""
    w = wp.tid()
    t = clock[0]
    f = wp.vec3(0.0, 0.0, 0.0)
    if start[w] >= 0 and t >= start[w] and t < start[w] + steps:
        f = force[w]
    xfrc[w, body] = wp.spatial_vector(f[0], f[1], f[2], 0.0, 0.0, 0.0)


@wp.kernel
def fall(clock: wp.array(dtype=int), qpos: wp.array2d(dtype=float), free_q: int,
         height: float, cos_tilt: float, done: wp.array(dtype=int),
         fall_step: wp.array(dtype=int), nefc: wp.array(dtype=int),
         nacon: wp.array(dtype=int), peak: wp.array(dtype=int)):
    """The first physics step after which a running world's torso is fallen (lower than
    ``height`` or tilted past ``acos(cos_tilt)``); the largest constraint and contact counts."""
    w = wp.tid()
    if done[w] == 0 and fall_step[w] < 0:
        qx = qpos[w, free_q + 4]
        qy = qpos[w, free_q + 5]
        up_z = 1.0 - 2.0 * (qx * qx + qy * qy)
        if qpos[w, free_q + 2] < height or up_z < cos_tilt:
            fall_step[w] = clock[0]
    wp.atomic_max(peak, 0, nefc[w])
    if w == 0:
        wp.atomic_max(peak, 1, nacon[0])


@wp.kernel
def advance(clock: wp.array(dtype=int), slot: int):
    clock[slot] = clock[slot] + 1


@wp.kernel
def record(clock: wp.array(dtype=int), time: wp.array(dtype=float),
           qpos: wp.array2d(dtype=float), qvel: wp.array2d(dtype=float), free_q: int,
           free_v: int, nq: int, nv: int, with_states: int, fall_step: wp.array(dtype=int),
           done: wp.array(dtype=int), torso: wp.array3d(dtype=float),
           states: wp.array3d(dtype=float), alive: wp.array(dtype=int)):
    """After control step ``c``: the torso (and the state) of every world that ran it at
    ``c + 1``; a world that fell in it is done from now on; ``alive``: how many run on."""
    w = wp.tid()
    if done[w] != 0:
        return
    r = clock[1] + 1
    for i in range(7):
        torso[w, r, i] = qpos[w, free_q + i]
    for i in range(6):
        torso[w, r, 7 + i] = qvel[w, free_v + i]
    if with_states != 0:
        states[w, r, 0] = time[w]
        for i in range(nq):
            states[w, r, 1 + i] = qpos[w, i]
        for i in range(nv):
            states[w, r, 1 + nq + i] = qvel[w, i]
    if fall_step[w] >= 0:
        done[w] = 1
    else:
        wp.atomic_add(alive, 0, 1)


# -- the policy's forward pass (evomotion.sim.warp_policy) ---------------------------------
@wp.kernel
def normalise(obs: wp.array2d(dtype=float), mean: wp.array2d(dtype=float),
              std: wp.array2d(dtype=float), clip: float, x: wp.array2d(dtype=float)):
    """``x = clip((obs - mean) / std, -clip, clip)`` (ARS V2 normalisation)."""
    w, j = wp.tid()
    x[w, j] = wp.clamp((obs[w, j] - mean[w, j]) / std[w, j], -clip, clip)


@wp.kernel
def dense(weights: wp.array3d(dtype=float), bias: wp.array2d(dtype=float), has_bias: int,
          squash: int, x: wp.array2d(dtype=float), y: wp.array2d(dtype=float)):
    """``y[w, i] = (tanh)(sum_j W[w, i, j] x[w, j] (+ b[w, i]))``: one thread per unit."""
    w, i = wp.tid()
    s = float(0.0)  # noqa: UP018 (a Warp variable, not a constant)
    for j in range(x.shape[1]):
        s += weights[w, i, j] * x[w, j]
    if has_bias != 0:
        s += bias[w, i]
    if squash != 0:
        s = wp.tanh(s)
    y[w, i] = s


@wp.kernel
def action_map(y: wp.array2d(dtype=float), scale: wp.array(dtype=float),
               offset: wp.array(dtype=float), low: wp.array(dtype=float),
               high: wp.array(dtype=float), out: wp.array2d(dtype=float)):
    """``out = clip(offset + scale * y, low, high)``."""
    w, j = wp.tid()
    out[w, j] = wp.clamp(offset[j] + scale[j] * y[w, j], low[j], high[j])
