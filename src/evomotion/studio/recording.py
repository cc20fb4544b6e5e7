"""The recorded frames the 3D player shows: a scene's model (the NAO's, a study's declared
scene, e.g. the kick's with its ball, or another robot of :mod:`evomotion.sim.robots`), the geoms
MuJoCo's viewer draws, and the body poses of a motion's physics replay or of a closed-loop
episode as it happened.

The geometry is the simulation's own MJCF: :func:`geom_table` lists every geom MuJoCo's viewer
draws by default (groups 0-2, alpha > 0; the NAO's visual geoms are group 1, its collision
geoms group 3 are hidden; planes are skipped: the scene's grid is the floor), with its colour
(the geom's rgba, or its material's when the rgba is MuJoCo's default, as MuJoCo renders it).

The poses come from the physics replay: the open-loop targets of
:func:`evomotion.sim.robots.nao.replay.motion_targets` (as ``evomotion replay``) from the
robot at rest in the motion's first pose (a study's scene: its own initial state, e.g. the
kick's ball in front of the foot), rolled out with
:class:`~evomotion.sim.rollout.BatchSimulator`; every ``1 / fps`` s (frame 0: the initial
state) ``mj_kinematics`` turns the state's ``qpos`` into geom and body poses. The browser shows
what the simulation did, falls included. Scene ``"robot:<spec>"`` (a bundled spec name or a
spec path, as ``--robot`` takes it): that robot from its initial state, the motion's channels
interpolated by :func:`evomotion.sim.play.motion_controls`, its own fall thresholds. A
:class:`~evomotion.studies.view.Played` closed-loop episode is not replayed: its states are
shown as they are.
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from evomotion.core.checks import check_choice, check_number
from evomotion.errors import InputError

#: "nao", a study's scene (its :class:`~evomotion.studies.view.Scene`'s name, e.g. the kick's
#: "kick") or "robot:<spec>"
VISUAL_GROUPS = (0, 1, 2)  # the groups MuJoCo's viewer shows by default
_TYPES = {mujoco.mjtGeom.mjGEOM_BOX: "box", mujoco.mjtGeom.mjGEOM_SPHERE: "sphere",
          mujoco.mjtGeom.mjGEOM_CAPSULE: "capsule", mujoco.mjtGeom.mjGEOM_CYLINDER: "cylinder",
          mujoco.mjtGeom.mjGEOM_ELLIPSOID: "ellipsoid", mujoco.mjtGeom.mjGEOM_MESH: "mesh"}
_TYPES = {int(k): v for k, v in _TYPES.items()}
_MODELS: dict[str, mujoco.MjModel] = {}
NAO_TORSO_HEIGHT_M = 0.33  # the NAO's torso origin standing: the default camera's scale
_CACHE: dict[tuple, dict[str, Any]] = {}
_CACHE_SIZE = 8
#: the longest motion the player replays (its physics is recorded in memory)
MAX_PLAY_S = 120.0


def study_scenes() -> dict[str, Any]:
    """The 3D scenes the registered studies declare (:class:`~evomotion.studies.view.Scene`),
    by name."""
    from evomotion.studies import all_studies

    return {s.view.scene.name: s.view.scene for s in all_studies()
            if s.view is not None and s.view.scene is not None}


def _study_scene(scene: str) -> Any:
    """The study's :class:`~evomotion.studies.view.Scene` named ``scene`` (``None``: the
    NAO's own scene "nao"); an unknown name is one :class:`InputError` line."""
    if scene == "nao":
        return None
    found = study_scenes()
    check_choice("scene", scene, ("nao", *found))
    return found.get(scene)


def load_scene_model(scene: str = "nao") -> mujoco.MjModel:
    """The model of ``scene`` ("nao": the NAO on its floor; a study's scene, e.g. "kick": the
    NAO and the ball); one shared instance per scene, not to be modified."""
    if scene.startswith("robot:"):  # load_robot caches it (and reloads an edited spec)
        return _robot(scene).model
    if scene not in _MODELS:
        declared = _study_scene(scene)
        if declared is not None:
            _MODELS[scene] = declared.load_model()
        else:
            from evomotion.sim.robots import nao

            _MODELS[scene] = nao.load_model()
    return _MODELS[scene]


def geom_rgba(model: mujoco.MjModel, i: int) -> np.ndarray:
    """The colour MuJoCo draws geom ``i`` with: its material's rgba when its own is the
    default (0.5, 0.5, 0.5, 1)."""
    rgba = model.geom_rgba[i]
    mat = int(model.geom_matid[i])
    if mat >= 0 and np.allclose(rgba, [0.5, 0.5, 0.5, 1.0]):
        rgba = model.mat_rgba[mat]
    return np.array(rgba, dtype=float)


def geom_table(model: mujoco.MjModel) -> list[dict[str, Any]]:
    """The drawn geoms: ``id, name, body, type`` (box, sphere, capsule, cylinder, ellipsoid,
    mesh), ``size`` (MuJoCo's), ``rgba``, ``pos``/``mat`` in the body frame, and for meshes
    ``vertices[n, 3]`` (geom frame) and ``faces[m, 3]``."""
    out = []
    for i in range(model.ngeom):
        kind = _TYPES.get(int(model.geom_type[i]))
        rgba = geom_rgba(model, i)
        if kind is None or int(model.geom_group[i]) not in VISUAL_GROUPS or rgba[3] <= 0:
            continue
        mat = np.empty(9)
        mujoco.mju_quat2Mat(mat, model.geom_quat[i])
        row = {"id": i, "name": model.geom(i).name, "body": int(model.geom_bodyid[i]),
               "type": kind, "size": model.geom_size[i].tolist(), "rgba": rgba.tolist(),
               "pos": model.geom_pos[i].tolist(), "mat": mat.reshape(3, 3).tolist()}
        if kind == "mesh":
            m = int(model.geom_dataid[i])
            v0, f0 = int(model.mesh_vertadr[m]), int(model.mesh_faceadr[m])
            row["vertices"] = model.mesh_vert[v0:v0 + int(model.mesh_vertnum[m])].copy()
            row["faces"] = model.mesh_face[f0:f0 + int(model.mesh_facenum[m])].copy()
        out.append(row)
    return out


def mesh_stl(vertices: np.ndarray, faces: np.ndarray) -> bytes:
    """A binary STL of the triangles ``faces[m, 3]`` (indices into ``vertices[n, 3]``)."""
    tri = np.asarray(vertices, dtype=np.float32)[np.asarray(faces, dtype=np.int64)]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
    rec = np.zeros(len(tri), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    rec["n"], rec["v"] = normal, tri
    return b"evomotion".ljust(80, b" ") + struct.pack("<I", len(tri)) + rec.tobytes()


def _initial_state(model: mujoco.MjModel, scene: str, pose: np.ndarray) -> np.ndarray:
    from evomotion.sim.robots import nao

    declared = _study_scene(scene)
    if declared is not None:
        return declared.initial_state(model, pose)
    return nao.initial_state(model, pose)


def _robot(scene: str) -> Any:
    """The robot of scene ``"robot:<spec>"``, loaded only when the studio may load it
    (:func:`~evomotion.studio.readers.check_robot`: a bundled name or a bounded spec file)."""
    from evomotion.sim.robots import load_robot
    from evomotion.studio.readers import check_robot

    return load_robot(check_robot(scene.split(":", 1)[1]))


def _record(path: Any, scene: str, fps: float, hold_s: float) -> dict[str, Any]:
    """The recording of a ``.motion`` file ``path`` or of a :class:`Motion` (a study's
    genome turned into a motion)."""
    from evomotion.sim.motion import Motion, read_motion
    from evomotion.sim.robots import nao
    from evomotion.sim.robots.nao.replay import MAX_HOLD_S, motion_targets
    from evomotion.sim.rollout import BatchSimulator, fall_step, torso_track

    check_number("fps", fps, lo=0.0, lo_open=True, hi=1000.0)
    check_number("hold_s", hold_s, lo=0.0, hi=MAX_HOLD_S)
    model = load_scene_model(scene)
    robot = _robot(scene) if scene.startswith("robot:") else None
    motion = path if isinstance(path, Motion) else \
        read_motion(path, None if robot is None else robot.joints)
    if not motion.duration_s <= MAX_PLAY_S:
        raise InputError(f"{path}: the 3D player plays motions of at most {MAX_PLAY_S:g} s, "
                         f"this one lasts {motion.duration_s:g} s")
    dt = float(model.opt.timestep)
    nstep = int(np.ceil((motion.duration_s + hold_s) / dt))
    if robot is None:
        first, ctrl = motion_targets(motion, dt, nstep)
        state0 = _initial_state(model, scene, first)
        limits = nao.FALL_HEIGHT_M, nao.FALL_TILT_RAD
    else:  # another robot: from its initial state, as the studies evaluate and play it
        from evomotion.sim.play import motion_controls

        ctrl, state0 = motion_controls(robot, motion, dt, nstep), robot.state0
        limits = robot.fall_height_m, robot.fall_tilt_rad
    with BatchSimulator(model, 1) as sim:
        states = sim.run(state0, ctrl[None])[0]
    fall = int(fall_step(torso_track(states[None]), *limits)[0])
    every = max(1, int(round(1.0 / (fps * dt))))
    steps = np.arange(0, nstep + 1, every)  # physics steps done before each frame
    # each frame's full state and the targets of the step after it (the analysis's forces)
    frame_states = np.concatenate([np.asarray(state0, float)[None], states[steps[1:] - 1]])
    frame_ctrl = np.asarray(ctrl, float)[np.minimum(steps, len(ctrl) - 1)]
    rec = _frames(model, frame_states, frame_ctrl, steps * dt)
    rec.update(scene=scene, frame_dt_s=every * dt, duration_s=nstep * dt,
               motion_s=float(motion.duration_s), fell=fall < nstep,
               fall_time_s=float((fall + 1) * dt) if fall < nstep else None)
    return rec


def _played(played: Any, scene: str, fps: float) -> dict[str, Any]:
    """The recording of a closed-loop episode (:class:`~evomotion.studies.view.Played`): its
    states as they are (every ``k``-th, near ``fps`` frames per second)."""
    from evomotion.sim.state import state_size

    check_number("fps", fps, lo=0.0, lo_open=True, hi=1000.0)
    model = load_scene_model(scene)
    states = np.asarray(played.states, float)
    ctrl = np.asarray(played.ctrl, float)
    if states.ndim != 2 or ctrl.shape != (len(states), model.nu) or len(states) < 1 or \
            states.shape[1] != state_size(model):
        raise InputError(f"played episode: states {states.shape} and targets {ctrl.shape} do "
                         f"not fit the {scene} scene's model ({model.nu} actuators)")
    dt = float(played.frame_dt_s)
    every = max(1, int(round(1.0 / (fps * dt))))
    k = np.arange(0, len(states), every)
    rec = _frames(model, states[k], ctrl[k], k * dt)
    end = (len(states) - 1) * dt
    rec.update(scene=scene, frame_dt_s=every * dt, duration_s=end, motion_s=end,
               fell=played.fall_time_s is not None, fall_time_s=played.fall_time_s)
    return rec


def _frames(model: mujoco.MjModel, frame_states: np.ndarray, frame_ctrl: np.ndarray,
            t_s: np.ndarray) -> dict[str, Any]:
    """The geom and body poses of each frame's state (``mj_kinematics``), read only."""
    from evomotion.sim.robots import nao

    qpos = nao.state_qpos_all(model, frame_states)
    table = geom_table(model)
    geoms = np.array([g["id"] for g in table], dtype=int)
    bodies = np.array(sorted({g["body"] for g in table}), dtype=int)
    n = len(qpos)
    pos, mat = np.empty((n, len(geoms), 3)), np.empty((n, len(geoms), 3, 3))
    bpos, bmat = np.empty((n, len(bodies), 3)), np.empty((n, len(bodies), 3, 3))
    data = mujoco.MjData(model)
    for k, q in enumerate(qpos):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        pos[k], mat[k] = data.geom_xpos[geoms], data.geom_xmat[geoms].reshape(-1, 3, 3)
        bpos[k], bmat[k] = data.xpos[bodies], data.xmat[bodies].reshape(-1, 3, 3)
    rec = {"t_s": np.asarray(t_s, float), "geoms": geoms, "pos": pos, "mat": mat,
           "bodies": bodies, "body_pos": bpos, "body_mat": bmat,
           "frame_states": np.asarray(frame_states, float),
           "frame_ctrl": np.asarray(frame_ctrl, float)}
    for a in rec.values():
        a.setflags(write=False)  # shared through the cache
    return rec


def record_poses(motion_path: Any, scene: str = "nao", fps: float = 25.0,
                 hold_s: float = 0.5) -> dict[str, Any]:
    """Replay the motion (and hold its last pose ``hold_s``) and record, at ``fps``:
    ``t_s[T]`` (from 0), ``geoms[G]`` (the ids of :func:`geom_table`), their world poses
    ``pos[T, G, 3]`` and ``mat[T, G, 3, 3]``, the bodies holding them ``bodies[B]`` with
    ``body_pos[T, B, 3]``/``body_mat[T, B, 3, 3]``; each frame's full physics state
    ``frame_states[T, ns]`` and the servo targets of the step after it ``frame_ctrl[T, nu]``;
    ``fell``, ``fall_time_s``, ``duration_s``
    (motion + hold), ``motion_s``, ``frame_dt_s``. Cached (read only) by file, mtime and
    arguments (the last few). ``motion_path`` may also be a
    :class:`~evomotion.sim.motion.Motion` (cached by its content) or a
    :class:`~evomotion.studies.view.Played` closed-loop episode (not replayed: its states are
    recorded as they are; cached by its content)."""
    import hashlib

    from evomotion.sim.motion import Motion
    from evomotion.studies.view import Played

    source = motion_path
    if isinstance(source, Played):
        digest = hashlib.sha256(np.ascontiguousarray(source.states, float).tobytes() +
                                np.ascontiguousarray(source.ctrl, float).tobytes()).hexdigest()
        key: tuple = ("played", digest, float(source.frame_dt_s), scene, float(fps))
    elif isinstance(source, Motion):
        digest = hashlib.sha256(repr(source.joints).encode() +
                                np.asarray(source.times_ms).tobytes() +
                                np.asarray(source.values, float).tobytes()).hexdigest()
        key = ("motion", digest, scene, float(fps), float(hold_s))
    else:
        source = path = Path(motion_path)
        key = (str(path.resolve()), path.stat().st_mtime_ns, scene, float(fps), float(hold_s))
    rec = _CACHE.pop(key, None) or (_played(source, scene, fps) if isinstance(source, Played)
                                    else _record(source, scene, fps, hold_s))
    _CACHE[key] = rec  # most recently used last
    while len(_CACHE) > _CACHE_SIZE:
        _CACHE.pop(next(iter(_CACHE)))
    return rec
