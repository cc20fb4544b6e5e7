"""The NAO (or the kick scene with its ball) playing a ``.motion`` in 3D in the browser.

The geometry is the model's own: every visual geom of the MJCF (groups 0 and 1; the collision
geoms of group 3 are hidden, as in MuJoCo's viewer) becomes a three.js object of NiceGUI's
scene: boxes, spheres, cylinders, capsules (a cylinder and two spheres) and ellipsoids (a
scaled sphere); the NAO model has no meshes (a mesh geom would be drawn as its bounding box).
Geoms are placed once inside one group per body; the poses come from the physics replay
(:func:`evomotion.sim.nao.replay.motion_targets`, the same open-loop targets as ``evomotion
replay``), recorded at ``fps`` and turned into body poses with ``mj_kinematics``, so the browser
shows exactly what the simulation did, falls included.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

VISUAL_GROUPS = (0, 1)
_CACHE: dict[tuple, dict] = {}


def load_scene_model(scene: str = "nao") -> mujoco.MjModel:
    if scene == "kick":
        from evomotion.studies.biped_kick.scene import load_scene

        return load_scene()
    from evomotion.sim import nao

    return nao.load_model()


def geom_table(model: mujoco.MjModel) -> list[dict[str, Any]]:
    """The visual geoms: id, body, type name, size, rgba, pose in the body frame."""
    names = {int(mujoco.mjtGeom.mjGEOM_BOX): "box", int(mujoco.mjtGeom.mjGEOM_SPHERE): "sphere",
             int(mujoco.mjtGeom.mjGEOM_CAPSULE): "capsule",
             int(mujoco.mjtGeom.mjGEOM_CYLINDER): "cylinder",
             int(mujoco.mjtGeom.mjGEOM_ELLIPSOID): "ellipsoid",
             int(mujoco.mjtGeom.mjGEOM_MESH): "mesh"}
    out = []
    for i in range(model.ngeom):
        kind = names.get(int(model.geom_type[i]))
        if kind is None or int(model.geom_group[i]) not in VISUAL_GROUPS \
                or model.geom_rgba[i, 3] == 0 or model.geom_bodyid[i] == 0:
            continue
        mat = np.zeros(9)
        mujoco.mju_quat2Mat(mat, model.geom_quat[i])
        size = model.geom_size[i].copy()
        if kind == "mesh":  # its bounding box (geom_aabb: centre, half sizes)
            kind, size = "box", model.geom_aabb[i, 3:].copy()
        out.append({"id": i, "body": int(model.geom_bodyid[i]), "type": kind,
                    "size": size.tolist(), "rgba": model.geom_rgba[i].tolist(),
                    "pos": model.geom_pos[i].tolist(), "mat": mat.reshape(3, 3).tolist()})
    return out


def record_poses(motion_path: Path | str, scene: str = "nao", fps: float = 25.0,
                 hold_s: float = 0.5) -> dict[str, Any]:
    """Replay the motion and record the world pose of every body with visual geoms:
    ``t_s[T]``, ``bodies[B]``, ``pos[T, B, 3]``, ``mat[T, B, 3, 3]``, ``fell``."""
    path = Path(motion_path)
    key = (str(path), path.stat().st_mtime, scene, fps, hold_s)
    if key in _CACHE:
        return _CACHE[key]
    from evomotion.sim import nao
    from evomotion.sim.nao.motion import read_motion
    from evomotion.sim.nao.replay import motion_targets
    from evomotion.sim.rollout import BatchSimulator, fall_step, torso_track

    model = load_scene_model(scene)
    motion = read_motion(path)
    dt = float(model.opt.timestep)
    nstep = int(np.ceil((motion.duration_s + hold_s) / dt))
    first, ctrl = motion_targets(motion, dt, nstep)
    if scene == "kick":
        from evomotion.studies.biped_kick.scene import default_ball_xy, initial_scene_state

        state0 = initial_scene_state(model, default_ball_xy(model, pose=first), first)
    else:
        state0 = nao.initial_state(model, first)
    with BatchSimulator(model, 1) as sim:
        states = sim.run(state0, ctrl[None])
    track = torso_track(states)
    fall = int(fall_step(track, nao.FALL_HEIGHT_M, nao.FALL_TILT_RAD)[0])
    every = max(1, int(round(1.0 / (fps * dt))))
    keep = np.arange(every - 1, nstep, every)
    qpos = nao.state_qpos_all(model, states[0, keep])
    bodies = sorted({g["body"] for g in geom_table(model)})
    data = mujoco.MjData(model)
    pos = np.empty((len(keep), len(bodies), 3))
    mat = np.empty((len(keep), len(bodies), 3, 3))
    for k, q in enumerate(qpos):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        pos[k] = data.xpos[bodies]
        mat[k] = data.xmat[bodies].reshape(-1, 3, 3)
    rec = {"t_s": (keep + 1) * dt, "bodies": bodies, "pos": pos, "mat": mat,
           "fell": fall < nstep, "duration_s": nstep * dt}
    if len(_CACHE) > 16:
        _CACHE.clear()
    _CACHE[key] = rec
    return rec


def _colour(rgba: list[float]) -> tuple[str, float]:
    r, g, b, a = rgba
    return f"#{int(r * 255):02x}{int(g * 255):02x}{int(b * 255):02x}", float(a)


def _add_geom(scene: Any, g: dict[str, Any]) -> None:
    colour, opacity = _colour(g["rgba"])
    s = g["size"]
    with scene.group().move(*g["pos"]).rotate_R(g["mat"]):
        if g["type"] == "box":
            scene.box(2 * s[0], 2 * s[1], 2 * s[2]).material(colour, opacity)
        elif g["type"] == "sphere":
            scene.sphere(s[0], 16, 12).material(colour, opacity)
        elif g["type"] == "ellipsoid":
            scene.sphere(1.0, 16, 12).scale(*s[:3]).material(colour, opacity)
        else:  # cylinder / capsule: three.js cylinders run along y, MuJoCo's along z
            scene.cylinder(s[0], s[0], 2 * s[1], 16).rotate(math.pi / 2, 0, 0) \
                .material(colour, opacity)
            if g["type"] == "capsule":
                for z in (-s[1], s[1]):
                    scene.sphere(s[0], 16, 8).move(0, 0, z).material(colour, opacity)


class NaoPlayer:
    """A 3D view with play/pause, a scrub slider and the time; built in the current NiceGUI
    container."""

    def __init__(self, motion_path: Path | str, scene: str = "nao", height: int = 420,
                 fps: float = 20.0) -> None:
        from nicegui import ui

        self.rec = record_poses(motion_path, scene, fps)
        model = load_scene_model(scene)
        geoms = geom_table(model)
        n = len(self.rec["t_s"])
        with ui.row().classes("items-center"):
            self.play_b = ui.button(icon="pause", on_click=self.toggle).classes("nao-play")
            self.slider = ui.slider(min=0, max=n - 1, value=0,
                                    on_change=lambda e: self.show(int(e.value))) \
                .classes("w-96 nao-scrub")
            self.label = ui.label().classes("nao-time font-mono")
            ui.label("fell" if self.rec["fell"] else "stayed up").classes(
                "text-red-700" if self.rec["fell"] else "text-green-700")
        with ui.scene(width=720, height=height, grid=(6, 60),
                      background_color="#f4f6f8").classes("nao-scene") as self.scene:
            self.scene.move_camera(x=0.55, y=-0.65, z=0.45, look_at_x=0.1, look_at_y=0,
                                   look_at_z=0.22, duration=0)
            self.groups = []
            for b in self.rec["bodies"]:
                with self.scene.group() as grp:
                    for g in geoms:
                        if g["body"] == b:
                            _add_geom(self.scene, g)
                self.groups.append(grp)
        self.playing = True
        self.frame = 0
        self.show(0)
        self.timer = ui.timer(1.0 / fps, self.advance)

    def show(self, k: int) -> None:
        k = max(0, min(k, len(self.rec["t_s"]) - 1))
        self.frame = k
        for grp, p, m in zip(self.groups, self.rec["pos"][k], self.rec["mat"][k], strict=True):
            grp.move(*p.tolist()).rotate_R(m.tolist())
        self.label.set_text(f"t = {self.rec['t_s'][k]:5.2f} s")

    def advance(self) -> None:
        if not self.playing:
            return
        k = (self.frame + 1) % len(self.rec["t_s"])
        self.slider.set_value(k)  # its handler shows the frame

    def toggle(self) -> None:
        self.playing = not self.playing
        self.play_b.props(f"icon={'pause' if self.playing else 'play_arrow'}")
