"""A decoded walk as Webots motions: start-up, one cycle, stop, and the whole walk.

The walk of one genome is three motions on the 20 ms pose grid (times from 0 in each file):

- ``start``: from the initial crouch to the end of the rising ramp (``READY_S`` + 2 cycles);
- ``cycle``: one steady cycle, first and last pose equal (play it again and again);
- ``stop``: the falling ramp, from a cycle's start to the ready pose.

The whole walk is ``start + n x cycle + stop`` with ``n = ceil(walk_s / T)``, assembled from
exactly those poses (:func:`assemble`), and it is what the problem evaluates: the exported
``best.motion`` and the three parts are the evaluated motion, pose for pose.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evomotion.sim.motion import Motion
from evomotion.sim.robots import nao
from evomotion.studies.humanoid_walk import foot_gait


@dataclass(frozen=True)
class WalkParts:
    start: Motion
    cycle: Motion
    stop: Motion
    cycles: int  # steady cycles of the whole walk
    schedule: foot_gait.Schedule


def parts_batch(genes: np.ndarray, s: foot_gait.Schedule) -> tuple[np.ndarray, ...]:
    """Poses ``(start[P, a, 22], cycle[P, c + 1, 22], stop[P, b, 22])`` of genomes sharing the
    schedule ``s``; the cycle's last pose is its first (a loop), ``stop`` starts at a cycle
    start (its first pose is the cycle's first too)."""
    ms = foot_gait.POSE_MS
    a = s.ready_ms + s.ramp_ms
    t_start = np.arange(0, a + 1, ms, dtype=np.int64)
    t_cycle = np.arange(a, a + s.period_ms, ms, dtype=np.int64)
    t_stop = np.arange(s.walk_end_ms - s.ramp_ms, s.walk_end_ms + 1, ms, dtype=np.int64)
    q = foot_gait.joint_targets(genes, np.concatenate([t_start, t_cycle, t_stop]), s)
    start, cycle, stop = np.split(q, [t_start.size, t_start.size + t_cycle.size], axis=1)
    # one pose per phase: the cycle closes on its own first pose, the stop opens on it
    cycle = np.concatenate([cycle, cycle[:, :1]], axis=1)
    start[:, -1] = cycle[:, 0]
    stop[:, 0] = cycle[:, 0]
    return start, cycle, stop


def assemble_poses(start: np.ndarray, cycle: np.ndarray, n: int,
                   stop: np.ndarray) -> np.ndarray:
    """Poses ``[..., K, 22]`` of ``start + n x cycle + stop`` (shared end poses once)."""
    loop = np.concatenate([cycle[..., :-1, :]] * n, axis=-2)
    return np.concatenate([start[..., :-1, :], loop, stop], axis=-2)


def _times(k: int) -> np.ndarray:
    return np.arange(k, dtype=np.int64) * foot_gait.POSE_MS


def walk_parts(genes: np.ndarray, walk_s: float) -> WalkParts:
    """The three motions of one genome."""
    g = np.asarray(genes, dtype=float)
    s = foot_gait.schedule(float(g[foot_gait.INDEX["period_s"]]), walk_s, 0.0)
    start, cycle, stop = (Motion(nao.JOINTS, _times(len(p[0])), p[0])
                          for p in parts_batch(g[None], s))
    return WalkParts(start, cycle, stop, cycles=s.steady_ms // s.period_ms, schedule=s)


def assemble(parts: WalkParts) -> Motion:
    """The whole walk as one motion."""
    q = assemble_poses(parts.start.values, parts.cycle.values, parts.cycles, parts.stop.values)
    return Motion(nao.JOINTS, _times(len(q)), q)


def whole_walk(genes: np.ndarray, walk_s: float) -> Motion:
    return assemble(walk_parts(genes, walk_s))
