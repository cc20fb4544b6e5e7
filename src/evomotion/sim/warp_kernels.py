"""Warp kernels around :func:`mujoco_warp.step` for open-loop batch rollouts.

One physics step of the batch is ``load_ctrl`` (the step's targets from a device buffer of the
whole segment), ``push`` (a torso impulse in the one step it is due), ``mujoco_warp.step``,
``store`` (time, qpos, qvel and sensor values into the segment's recording, in the
``mjSTATE_FULLPHYSICS`` layout of :mod:`mujoco.rollout`; the largest contact and constraint
counts seen, for the overflow check) and ``advance`` (the step counter, read on the device, so
one captured CUDA graph replays every step). Imported only with ``problem.backend = "warp"``.
"""

from __future__ import annotations

import warp as wp


@wp.kernel
def load_ctrl(ctrl: wp.array3d(dtype=float), step: wp.array(dtype=int),
              out: wp.array2d(dtype=float)):
    """``out[w, j] = ctrl[w, step, j]`` (``ctrl[world, segment step, actuator]``)."""
    w, j = wp.tid()
    out[w, j] = ctrl[w, step[0], j]


@wp.kernel
def push(step: wp.array(dtype=int), push_step: wp.array(dtype=int),
         force: wp.array(dtype=wp.vec3), body: int,
         xfrc: wp.array2d(dtype=wp.spatial_vector)):
    """The torso force ``force[w]`` (N) during segment step ``push_step[w]``, else none."""
    w = wp.tid()
    f = wp.vec3(0.0, 0.0, 0.0)
    if step[0] == push_step[w]:
        f = force[w]
    xfrc[w, body] = wp.spatial_vector(f[0], f[1], f[2], 0.0, 0.0, 0.0)


@wp.kernel
def store(step: wp.array(dtype=int), time: wp.array(dtype=float),
          qpos: wp.array2d(dtype=float), qvel: wp.array2d(dtype=float),
          sensordata: wp.array2d(dtype=float), nq: int, nv: int, nsensor: int,
          nefc: wp.array(dtype=int), nacon: wp.array(dtype=int),
          states: wp.array3d(dtype=float), sensors: wp.array3d(dtype=float),
          peak: wp.array(dtype=int)):
    """``states[w, step] = (time, qpos, qvel)``, ``sensors[w, step] = sensordata``;
    ``peak = (max constraint rows of a world, max contacts of the batch)`` so far."""
    w = wp.tid()
    t = step[0]
    states[w, t, 0] = time[w]
    for i in range(nq):
        states[w, t, 1 + i] = qpos[w, i]
    for i in range(nv):
        states[w, t, 1 + nq + i] = qvel[w, i]
    for i in range(nsensor):
        sensors[w, t, i] = sensordata[w, i]
    wp.atomic_max(peak, 0, nefc[w])
    if w == 0:
        wp.atomic_max(peak, 1, nacon[0])


@wp.kernel
def advance(step: wp.array(dtype=int)):
    step[0] = step[0] + 1
