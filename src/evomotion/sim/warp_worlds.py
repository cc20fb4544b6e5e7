"""Perturbed worlds on MuJoCo Warp: one batch, each trajectory with its own model fields.

:func:`evomotion.sim.worlds.simulate_worlds` with a :class:`~evomotion.sim.warp_rollout.
WarpSimulator` comes here. Each :class:`~evomotion.sim.worlds.World` is an edited copy of
the NAO model; the fields that differ between the worlds (friction, masses and inertias, the
torso's centre of mass, servo gains and force ranges, and what ``mj_setConst`` derived from
them) are found by comparing the models as MuJoCo Warp puts them on the device, and become
MuJoCo Warp batched model fields with one row per trajectory of the device batch. Pushes are
applied on the device (``xfrc_applied`` during the one step they are due), latencies are
already in the delayed controls.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from evomotion.sim.rollout import rollout_segments


def batchable_fields() -> list[str]:
    """MuJoCo Warp ``Model`` fields that may carry one row per world."""
    from mujoco_warp._src import types, warp_util

    return [f.name for f in dataclasses.fields(types.Model)
            if warp_util.is_array_spec(f.type) and getattr(f.type, "shape", ())[:1] == ("*",)]


def differing_fields(models: list) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """(``values[u, ...]`` of every batchable field that differs between the ``u`` distinct
    models of ``models``, ``index[len(models)]`` of each model among them)."""
    import mujoco_warp as mjw

    distinct: dict[int, int] = {}
    uniq: list = []
    index = np.empty(len(models), dtype=np.int64)
    for i, m in enumerate(models):
        if id(m) not in distinct:
            distinct[id(m)] = len(uniq)
            uniq.append(m)
        index[i] = distinct[id(m)]
    names = batchable_fields()
    device = [mjw.put_model(m) for m in uniq]
    fields = {}
    for name in names:
        rows = [getattr(wm, name).numpy()[0] for wm in device]
        if any(not np.array_equal(rows[0], r) for r in rows[1:]):
            fields[name] = np.stack(rows)
    return fields, index


def _cached_fields(sim, models: list) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """:func:`differing_fields` of ``models`` and ``sim``'s own model, that model's row
    dropped, kept on ``sim`` for the same worlds (every generation of a run evaluates the same
    K worlds, repeated per genome). Comparing with the simulator's model too: worlds that all
    agree on a field that differs from it (one perturbed world alone) still get their value."""
    distinct = list({id(m): m for m in models}.values())
    key = tuple(id(m) for m in distinct)
    cache = getattr(sim, "_world_fields", None)
    if cache is None or cache[0] != key or any(a is not b for a, b in zip(cache[1], distinct,
                                                                          strict=True)):
        with sim.wp.ScopedDevice(sim.device):
            fields, rows = differing_fields([sim.model, *distinct])
        fields = {name: v[rows[1:]] for name, v in fields.items()}  # distinct: its own order
        sim._world_fields = cache = (key, distinct, fields)
    fields = cache[2]
    position = {id(m): i for i, m in enumerate(cache[1])}
    return fields, np.array([position[id(m)] for m in models], dtype=np.int64)


def simulate_worlds_warp(sim, models: list, initial: np.ndarray, ctrl: np.ndarray,
                         push_ns: np.ndarray, push_step: np.ndarray, body: int,
                         stopped: Callable[[np.ndarray], np.ndarray] | None,
                         segment_steps: int) -> tuple[np.ndarray, np.ndarray]:
    """(``states[k, nstep, nstate]``, ``sensors[k, nstep, n]``) of ``k`` trajectories, the
    i-th in ``models[i]`` from ``initial[i]`` under ``ctrl[i]``, pushed by ``push_ns[i]``
    (N s) in step ``push_step[i]`` (-1: never), stopped early as in
    :func:`~evomotion.sim.rollout.rollout_segments`."""
    fields, index = _cached_fields(sim, models)
    dt = float(sim.model.opt.timestep)
    force = np.asarray(push_ns, dtype=float) / dt
    pushed = bool((np.asarray(push_step) >= 0).any())
    nstep = ctrl.shape[1]

    def roll(rows: np.ndarray, start: int, stop: int, init: np.ndarray):
        f = {name: v[index[rows]] for name, v in fields.items()}
        push = None
        if pushed:
            s = push_step[rows]
            rel = np.where((s >= start) & (s < stop), s - start, -1)
            push = (rel, force[rows], body)
        return sim.segment(init, ctrl[rows, start:stop], f or None, push)

    return rollout_segments(roll, initial, nstep, sim.model.nsensordata, stopped, segment_steps)
