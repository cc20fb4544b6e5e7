"""``run.loggers = ["rerun"]``: ``<run>/best.rrd``, the run as a rerun recording.

Open it with the rerun viewer (``rerun best.rrd``); nothing is spawned or sent over a network
while the run writes it. It is written once, at the end of the run, from ``stats.csv`` (so a
resumed run's recording is whole) and the study's replay of its best motion:

- ``fitness/best``, ``fitness/mean``, ``fitness/best_so_far``: scalar series on the
  ``generation`` and ``evaluations`` timelines;
- for studies whose ``replay`` hook plays their best motion (:class:`~evomotion.run.contracts.
  Replay`: the humanoid studies replay ``best.motion`` on the problem's own robot), that motion
  at :data:`FRAME_HZ` on the ``sim_time`` timeline: each body's pose (``robot/bodies/<body>``,
  a :class:`rerun.Transform3D`) with its shapes logged once under it (``boxes``, ``capsules``,
  ``ellipsoids``, ``cylinders``: the geoms MuJoCo shows by default), the root body's position
  (``robot/torso``) and its whole path (``robot/torso_path``).

An interrupted run writes no recording; its resumed run does.
"""

from __future__ import annotations

import inspect
from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr

from evomotion.run.context import RunContext
from evomotion.run.contracts import Replay, ReplayHook

NAME = "best.rrd"
FRAME_HZ = 50.0
SERIES = ("best", "mean", "best_so_far")
#: shape entity -> its rerun archetype (points where the installed SDK lacks one)
KINDS = {"boxes": "Boxes3D", "capsules": "Capsules3D", "ellipsoids": "Ellipsoids3D",
         "cylinders": "Cylinders3D"}


class Logger:
    def __init__(self, out_dir: Path, replay: ReplayHook | None = None) -> None:
        self.out_dir = Path(out_dir)
        self.replay = replay

    def row(self, row: dict[str, Any]) -> None:
        """Nothing: the series are read back from stats.csv at the end."""

    def close(self) -> None:
        pass

    def finish(self, ctx: RunContext) -> None:
        from evomotion.run.stats import read_stats

        tmp = self.out_dir / f".{NAME}.tmp"  # then renamed: best.rrd is whole or absent
        rec = rr.RecordingStream("evomotion")
        rec.save(tmp)
        try:
            rec.send_recording_name(f"{ctx.study} {self.out_dir.name}")
            stats = self.out_dir / "stats.csv"
            log_series(rec, read_stats(stats) if stats.exists() else {})
            replay = self.replay(ctx) if self.replay is not None else None
            if replay is not None:
                log_motion(rec, replay)
        except BaseException:
            rec.disconnect()
            tmp.unlink(missing_ok=True)
            raise
        rec.flush()
        rec.disconnect()
        tmp.replace(self.out_dir / NAME)


def log_series(rec: Any, stats: dict[str, np.ndarray]) -> None:
    """The fitness series of ``stats`` (:func:`~evomotion.run.stats.read_stats`)."""
    if not len(stats.get("generation", ())):
        return
    times = [rr.TimeColumn("generation", sequence=stats["generation"].astype(np.int64)),
             rr.TimeColumn("evaluations", sequence=stats["evaluations"].astype(np.int64))]
    for name in SERIES:
        if name in stats:
            rec.send_columns(f"fitness/{name}", indexes=times,
                             columns=rr.Scalars.columns(scalars=stats[name]))


def log_motion(rec: Any, replay: Replay) -> None:
    """The motion ``replay`` (see the module doc)."""
    import mujoco

    model, dt = replay.model, replay.dt
    stride = max(1, int(round(1.0 / (FRAME_HZ * dt))))
    qpos = np.asarray(replay.qpos)[::stride]
    data = mujoco.MjData(model)
    xpos = np.empty((len(qpos), model.nbody, 3))
    xquat = np.empty((len(qpos), model.nbody, 4))
    for f, q in enumerate(qpos):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        xpos[f], xquat[f] = data.xpos, data.xquat
    times = [rr.TimeColumn("sim_time", duration=np.arange(len(qpos)) * stride * dt)]
    rec.log("robot", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)  # MuJoCo's world: z up
    for b in range(1, model.nbody):  # body 0 is the world
        entity = f"robot/bodies/{rr.escape_entity_path_part(model.body(b).name or f'body{b}')}"
        rec.send_columns(entity, indexes=times, columns=rr.Transform3D.columns(
            translation=xpos[:, b], quaternion=xquat[:, b][:, [1, 2, 3, 0]]))  # wxyz -> xyzw
        for part, shapes in body_shapes(model, b).items():
            rec.log(f"{entity}/{part}", shapes, static=True)
    torso = replay.root_body
    rec.log("robot/torso_path", rr.LineStrips3D([xpos[:, torso]]), static=True)
    rec.send_columns("robot/torso", indexes=times, columns=rr.Points3D.columns(
        positions=xpos[:, torso]).partition(np.ones(len(qpos), dtype=np.int64)))


def body_shapes(model: Any, body: int) -> dict[str, Any]:
    """The rerun shapes of the geoms of ``body`` that MuJoCo shows by default (groups 0-2),
    in the body's frame: ``{"boxes": rr.Boxes3D, "capsules": ..., ...}``."""
    import mujoco

    G = mujoco.mjtGeom
    found: dict[str, dict[str, list[Any]]] = {}
    for g in np.flatnonzero(model.geom_bodyid == body):
        kind, size = int(model.geom_type[g]), model.geom_size[g]
        if model.geom_group[g] > 2 or kind not in (G.mjGEOM_BOX, G.mjGEOM_CAPSULE,
                                                   G.mjGEOM_SPHERE, G.mjGEOM_ELLIPSOID,
                                                   G.mjGEOM_CYLINDER):
            continue
        pos, wxyz = model.geom_pos[g], model.geom_quat[g]
        mat = model.mat_rgba[model.geom_matid[g]] if model.geom_matid[g] >= 0 \
            else model.geom_rgba[g]
        rgba = (np.clip(mat, 0, 1) * 255).astype(np.uint8)
        if kind == G.mjGEOM_CAPSULE:  # rerun's runs from its origin along +z; MuJoCo's is centred
            axis = np.empty(9)
            mujoco.mju_quat2Mat(axis, wxyz)
            shape = {"translations": pos - axis.reshape(3, 3)[:, 2] * size[1],
                     "lengths": 2 * size[1], "radii": size[0]}
            part = "capsules"
        elif kind == G.mjGEOM_CYLINDER:
            shape, part = {"centers": pos, "lengths": 2 * size[1], "radii": size[0]}, "cylinders"
        else:
            half = np.full(3, size[0]) if kind == G.mjGEOM_SPHERE else size
            part = "boxes" if kind == G.mjGEOM_BOX else "ellipsoids"
            shape = {"centers": pos, "half_sizes": half}
        rows = found.setdefault(part, {})
        for k, v in {**shape, "quaternions": wxyz[[1, 2, 3, 0]], "colors": rgba}.items():
            rows.setdefault(k, []).append(v)
    out = {}
    for part, lists in found.items():
        archetype: Any = getattr(rr, KINDS[part], None)
        arrays: dict[str, Any] = {k: np.asarray(v) for k, v in lists.items()}
        if archetype is None:  # an older SDK: the shapes' centres
            centres = arrays["centers"] if "centers" in arrays else arrays["translations"]
            out[part] = rr.Points3D(centres, colors=arrays["colors"])
            continue
        if "fill_mode" in inspect.signature(archetype.__init__).parameters:  # not every SDK
            arrays["fill_mode"] = "solid"
        out[part] = archetype(**arrays)
    return out
