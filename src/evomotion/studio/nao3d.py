"""The NAO (or the kick scene with its ball, or another robot of :mod:`evomotion.sim.robots`)
playing a ``.motion`` in 3D in the browser.

The geometry is the simulation's own MJCF: :func:`geom_table` lists every geom MuJoCo's viewer
draws by default (groups 0-2, alpha > 0; the NAO's visual geoms are group 1, its collision
geoms group 3 are hidden; planes are skipped: the scene's grid is the floor), with its colour
(the geom's rgba, or its material's when the rgba is MuJoCo's default, as MuJoCo renders it).
In NiceGUI's :class:`ui.scene` (three.js) boxes, spheres and cylinders are its primitives
(three.js cylinders run along y, MuJoCo's along z: a +90 degree turn about x), an ellipsoid is a
scaled sphere, a capsule a cylinder and two spheres in one group, and a mesh an STL built from
``mesh_vert``/``mesh_face`` and passed as a ``data:`` URL to ``scene.stl`` (the NAO model has
no meshes). The geoms are placed once in one group per body; a frame moves the body groups only
(one batched message per frame).

The poses come from the physics replay: the open-loop targets of
:func:`evomotion.sim.robots.nao.replay.motion_targets` (as ``evomotion replay``) from the
robot at rest in the motion's first pose (a study's scene: its own initial state, e.g. the
kick's ball in front of the foot), rolled out with
:class:`~evomotion.sim.rollout.BatchSimulator`; every ``1 / fps`` s (frame 0: the initial
state) ``mj_kinematics`` turns the state's ``qpos`` into geom and body poses. The browser shows
what the simulation did, falls included. Scene ``"robot:<spec>"`` (a bundled spec name or a
spec path, as ``--robot`` takes it): that robot from its initial state, the motion's channels
interpolated by :func:`evomotion.sim.play.motion_controls`, its own fall thresholds.
"""

from __future__ import annotations

import base64
import contextlib
import functools
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
_Y_TO_Z = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # +90 deg about x
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
    qpos = nao.state_qpos_all(model, frame_states)
    table = geom_table(model)
    geoms = np.array([g["id"] for g in table], dtype=int)
    bodies = np.array(sorted({g["body"] for g in table}), dtype=int)
    n = len(steps)
    pos, mat = np.empty((n, len(geoms), 3)), np.empty((n, len(geoms), 3, 3))
    bpos, bmat = np.empty((n, len(bodies), 3)), np.empty((n, len(bodies), 3, 3))
    data = mujoco.MjData(model)
    for k, q in enumerate(qpos):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        pos[k], mat[k] = data.geom_xpos[geoms], data.geom_xmat[geoms].reshape(-1, 3, 3)
        bpos[k], bmat[k] = data.xpos[bodies], data.xmat[bodies].reshape(-1, 3, 3)
    rec = {"t_s": steps * dt, "geoms": geoms, "pos": pos, "mat": mat, "bodies": bodies,
           "body_pos": bpos, "body_mat": bmat, "frame_states": frame_states,
           "frame_ctrl": frame_ctrl}
    for a in rec.values():
        a.setflags(write=False)  # shared through the cache
    rec.update(scene=scene, frame_dt_s=every * dt, duration_s=nstep * dt,
               motion_s=float(motion.duration_s), fell=fall < nstep,
               fall_time_s=float((fall + 1) * dt) if fall < nstep else None)
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
    :class:`~evomotion.sim.motion.Motion` (cached by its content)."""
    from evomotion.sim.motion import Motion

    if isinstance(motion_path, Motion):
        import hashlib

        m = motion_path
        digest = hashlib.sha256(repr(m.joints).encode() + np.asarray(m.times_ms).tobytes() +
                                np.asarray(m.values, float).tobytes()).hexdigest()
        key: tuple = ("motion", digest, scene, float(fps), float(hold_s))
        source: Any = m
    else:
        source = path = Path(motion_path)
        key = (str(path.resolve()), path.stat().st_mtime_ns, scene, float(fps), float(hold_s))
    rec = _CACHE.pop(key, None) or _record(source, scene, fps, hold_s)
    _CACHE[key] = rec  # most recently used last
    while len(_CACHE) > _CACHE_SIZE:
        _CACHE.pop(next(iter(_CACHE)))
    return rec


def _add_geom(scene: Any, g: dict[str, Any]) -> None:
    r, gr, b, a = g["rgba"]
    colour, opacity = f"#{round(r * 255):02x}{round(gr * 255):02x}{round(b * 255):02x}", a
    s, mat, kind = g["size"], np.array(g["mat"]), g["type"]
    if kind == "cylinder":  # three.js's axis y onto MuJoCo's z
        mat = mat @ _Y_TO_Z
    if kind == "box":
        obj = scene.box(2 * s[0], 2 * s[1], 2 * s[2])
    elif kind == "sphere":
        obj = scene.sphere(s[0], 24, 16)
    elif kind == "ellipsoid":
        obj = scene.sphere(1.0, 24, 16).scale(*s[:3])
    elif kind == "cylinder":
        obj = scene.cylinder(s[0], s[0], 2 * s[1], 24)
    elif kind == "mesh":
        url = "data:model/stl;base64," + base64.b64encode(
            mesh_stl(g["vertices"], g["faces"])).decode()
        obj = scene.stl(url)
    else:  # capsule: a cylinder and two spheres along the group's z
        with scene.group() as obj:
            scene.cylinder(s[0], s[0], 2 * s[1], 24).rotate_R(_Y_TO_Z.tolist()) \
                .material(colour, opacity)
            for z in (-s[1], s[1]):
                scene.sphere(s[0], 24, 12).move(0, 0, z).material(colour, opacity)
    if kind != "capsule":
        obj.material(colour, opacity)
    obj.move(*g["pos"]).rotate_R(mat.tolist())


#: NiceGUI's own render rate of the 3D scene: low, since the player renders the scene at every
#: animation frame itself (NiceGUI's loop, an animation frame then a 1 / fps s timeout, drew
#: one frame in two: 14-19 frames/s in headless Chromium's software WebGL)
SCENE_FPS = 5
#: playback speeds offered (slow motion)
SPEEDS = (1.0, 0.5, 0.25, 0.1)


def pose_stream(rec: dict[str, Any]) -> str:
    """The recording's body poses for the browser: float32 ``[frames, bodies, 7]`` (position,
    quaternion x y z w), base64."""
    from scipy.spatial.transform import Rotation

    f, b = rec["body_pos"].shape[:2]
    quat = Rotation.from_matrix(rec["body_mat"].reshape(-1, 3, 3)).as_quat().reshape(f, b, 4)
    out = np.concatenate([rec["body_pos"], quat], axis=2).astype("<f4")
    return base64.b64encode(out.tobytes()).decode()


@functools.cache
def _player_js() -> str:
    from importlib.resources import files

    return (files("evomotion.studio") / "nao_player.js").read_text(encoding="utf-8")


class NaoPlayer:
    """The motion playing in 3D (looping) in the browser: the poses are sent once and animated
    there (``nao_player.js``), with play/pause, frame stepping, a scrub slider
    (``nao-scrub``), slow motion, the time and whether the robot fell; built in the current
    NiceGUI container."""

    def __init__(self, motion_path: Any, scene: str = "nao", height: int = 420,
                 width: int = 640, fps: float = 25.0, analysis: bool = True) -> None:
        import html
        import json

        from nicegui import ui

        self.rec = rec = record_poses(motion_path, scene, fps)
        geoms = geom_table(load_scene_model(scene))
        self.nframe = len(rec["t_s"])
        camera = ui.scene.perspective_camera(fov=45, near=0.01, far=100)
        fell = f"fell at {rec['fall_time_s']:.2f} s" if rec["fell"] else "stayed up"
        controls = ui.html("", sanitize=False).classes("nao-controls")
        with ui.scene(width=width, height=height, grid=(6, 60), camera=camera,
                      background_color="#f4f6f8", fps=SCENE_FPS) as self.scene:
            self.scene.classes("nao-scene").props("data-testid=nao-scene")
            self.groups = []
            for b in rec["bodies"]:
                with self.scene.group() as group:
                    for g in geoms:
                        if g["body"] == b:
                            _add_geom(self.scene, g)
                self.groups.append(group)
        box = f"evo-player-{self.scene.id}"
        speeds = "".join(f'<option value="{v}">{v:g}x</option>' for v in SPEEDS)
        controls.set_content(
            f'<div id="{box}" class="flex items-center gap-3">'
            '<button class="nao-play q-btn px-2">pause</button>'
            '<button class="nao-back px-1" title="one frame back">&#9664;|</button>'
            '<button class="nao-fwd px-1" title="one frame on">|&#9654;</button>'
            f'<input type="range" class="nao-scrub w-80" min="0" max="{self.nframe - 1}" '
            'step="1" value="0">'
            '<span class="nao-time font-mono"></span>'
            f'<select class="nao-speed" title="playback speed">{speeds}</select>'
            f'<span class="{"text-red-700" if rec["fell"] else "text-green-700"}">'
            f'{html.escape(fell)}</span></div>')
        declared = None if scene.startswith("robot:") else _study_scene(scene)
        look_x = declared.look_x_m if declared is not None else 0.0
        size = 1.0  # the NAO's camera, scaled for another robot by its torso height
        if scene.startswith("robot:"):
            size = max(0.5, float(_robot(scene).state0[3]) / NAO_TORSO_HEIGHT_M)
        self.scene.move_camera(x=look_x + 0.75 * size, y=-0.6 * size, z=0.5 * size,
                               look_at_x=look_x, look_at_y=0.0, look_at_z=0.25 * size,
                               duration=0)
        self.show(0)  # the first pose, before the browser animates
        charts = self._analysis(ui, scene) if analysis else []
        dt = float(rec["frame_dt_s"])
        cfg = {"scene": self.scene.id, "groups": [g.id for g in self.groups],
               "controls": box, "data": pose_stream(rec), "nframe": self.nframe, "dt": dt,
               "duration": max(dt, (self.nframe - 1) * dt), "charts": [c.id for c in charts]}
        code = _player_js() + f"\nwindow.evoStartPlayer({json.dumps(cfg)});"
        ui.timer(0.05, lambda: ui.run_javascript(code), once=True)

    def _analysis(self, ui, scene: str) -> list[Any]:
        """Under the player: joint angles and tilt (pick any), foot contacts and heights, each
        with a cursor at the playing time (``nao_player.js`` moves it)."""
        from evomotion.sim.robots import load_robot
        from evomotion.studio import motion_traces as mt

        robot = _robot(scene) if scene.startswith("robot:") else load_robot("nao")
        tr = mt.traces(load_scene_model(scene), self.rec["frame_states"],
                       self.rec["frame_ctrl"], dict(robot.spec.feet))
        t = np.asarray(self.rec["t_s"], float)
        angles = mt.angle_series(tr, t)
        legs = [n for n in angles if any(k in n for k in ("KneePitch", "knee", "Knee"))][:2]
        shown = ["torso tilt", *legs]
        base = {"animation": False, "legend": {"top": 0},
                "tooltip": {"trigger": "axis", ":valueFormatter": "v => v == null ? '-' : "
                            "String(Number(Number(v).toPrecision(4)))"},
                "grid": {"left": 60, "right": 60, "top": 35, "bottom": 30},
                "xAxis": {"type": "value", "name": "t (s)", "min": 0,
                          "max": round(float(t[-1]), 3)}}
        pick = ui.select(list(angles), multiple=True, value=shown, label="angles (°)") \
            .classes("w-full motion-angles-pick").props("use-chips")
        angle_chart = ui.echart({**base, "yAxis": {"type": "value", "name": "°",
                                                   "scale": True},
                                 "series": [{"name": k, "type": "line", "showSymbol": False,
                                             "data": angles[k]} for k in shown]}) \
            .classes("w-full h-64 motion-angles")

        def repick() -> None:
            angle_chart.options["series"] = [{"name": k, "type": "line", "showSymbol": False,
                                              "data": angles[k]} for k in pick.value or []]
            angle_chart.update()

        pick.on_value_change(lambda _: repick())
        support = ui.echart({**base, "yAxis": [
            {"type": "value", "name": "feet", "min": 0, "max": max(1, len(tr["contact"])),
             "interval": 1}, {"type": "value", "name": "m", "scale": True}],
            "series": mt.support_series(tr, t)}).classes("w-full h-56 motion-support")
        balance = ui.echart({**base, "yAxis": {"type": "value", "name": "m", "scale": True},
                             "series": mt.balance_series(tr, t)}) \
            .classes("w-full h-56 motion-balance")
        return [angle_chart, support, balance]

    def show(self, k: int) -> None:
        """Put the bodies at frame ``k`` from the server (the initial pose)."""
        k = max(0, min(int(k), self.nframe - 1))
        batch = getattr(self.scene, "_batch_calls", None)  # NiceGUI's own batching
        with batch() if batch is not None else contextlib.nullcontext():
            for group, p, m in zip(self.groups, self.rec["body_pos"][k],
                                   self.rec["body_mat"][k], strict=True):
                group.move(*p.tolist()).rotate_R(m.tolist())
