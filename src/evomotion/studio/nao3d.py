"""The NAO (or the kick scene with its ball, or another robot of :mod:`evomotion.sim.robots`)
playing a ``.motion`` in 3D in the browser.

The recordings come from :mod:`.recording` (the scene's model, its drawn geoms, the physics
replay's or a closed-loop episode's body poses). In NiceGUI's :class:`ui.scene` (three.js) boxes,
spheres and cylinders are its primitives
(three.js cylinders run along y, MuJoCo's along z: a +90 degree turn about x), an ellipsoid is a
scaled sphere, a capsule a cylinder and two spheres in one group, and a mesh an STL built from
``mesh_vert``/``mesh_face`` and passed as a ``data:`` URL to ``scene.stl`` (the NAO model has
no meshes). The geoms are placed once in one group per body; the browser moves the body
groups (``nao_player.js``).
"""

from __future__ import annotations

import base64
import contextlib
import functools
from typing import Any

import numpy as np

from evomotion.studio.recording import (  # noqa: F401 - the player's recordings, re-exported
    MAX_PLAY_S,
    NAO_TORSO_HEIGHT_M,
    _robot,
    _study_scene,
    geom_table,
    load_scene_model,
    mesh_stl,
    record_poses,
    study_scenes,
)

_Y_TO_Z = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # +90 deg about x


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
#: the colour of a ghosted second motion (translucent blue)
GHOST_RGBA = (0.25, 0.5, 0.95, 0.35)


def _fell_text(rec: dict[str, Any]) -> str:
    return f"fell at {rec['fall_time_s']:.2f} s" if rec["fell"] else "stayed up"


def _body_groups(scene: Any, rec: dict[str, Any], geoms: list[dict[str, Any]],
                 rgba: tuple[float, ...] | None = None) -> list[Any]:
    """One ``ui.scene`` group per recorded body holding its geoms (all in ``rgba``: a
    ghost)."""
    groups = []
    for b in rec["bodies"]:
        with scene.group() as group:
            for g in geoms:
                if g["body"] == b:
                    _add_geom(scene, g if rgba is None else {**g, "rgba": list(rgba)})
        groups.append(group)
    return groups


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
                 width: int = 640, fps: float = 25.0, analysis: bool = True,
                 ghost: Any = None) -> None:
        import html
        import json

        from nicegui import ui

        self.rec = rec = record_poses(motion_path, scene, fps)
        # a second motion in the same scene, translucent, on the same clock
        self.ghost = None if ghost is None else record_poses(ghost, scene, fps)
        geoms = geom_table(load_scene_model(scene))
        self.nframe = len(rec["t_s"])
        frames = max(self.nframe, 0 if self.ghost is None else len(self.ghost["t_s"]))
        camera = ui.scene.perspective_camera(fov=45, near=0.01, far=100)
        fell = _fell_text(rec)
        if self.ghost is not None:
            fell += f"; ghost {_fell_text(self.ghost)}"
        controls = ui.html("", sanitize=False).classes("nao-controls")
        with ui.scene(width=width, height=height, grid=(6, 60), camera=camera,
                      background_color="#f4f6f8", fps=SCENE_FPS) as self.scene:
            self.scene.classes("nao-scene").props("data-testid=nao-scene")
            self.groups = _body_groups(self.scene, rec, geoms)
            self.ghost_groups = [] if self.ghost is None else \
                _body_groups(self.scene, self.ghost, geoms, GHOST_RGBA)
        box = f"evo-player-{self.scene.id}"
        speeds = "".join(f'<option value="{v}">{v:g}x</option>' for v in SPEEDS)
        controls.set_content(
            f'<div id="{box}" class="flex items-center gap-3">'
            '<button class="nao-play q-btn px-2">pause</button>'
            '<button class="nao-back px-1" title="one frame back">&#9664;|</button>'
            '<button class="nao-fwd px-1" title="one frame on">|&#9654;</button>'
            f'<input type="range" class="nao-scrub w-80" min="0" max="{frames - 1}" '
            'step="1" value="0">'
            '<span class="nao-time font-mono"></span>'
            f'<select class="nao-speed" title="playback speed">{speeds}</select>'
            f'<span class="nao-fell {"text-red-700" if rec["fell"] else "text-green-700"}">'
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
               "duration": max(dt, (frames - 1) * dt), "charts": [c.id for c in charts]}
        if self.ghost is not None:  # the same scene, so the same frame interval
            cfg["ghost"] = {"groups": [g.id for g in self.ghost_groups],
                            "data": pose_stream(self.ghost), "nframe": len(self.ghost["t_s"])}
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
        batch = getattr(self.scene, "_batch_calls", None)  # NiceGUI's own batching
        with batch() if batch is not None else contextlib.nullcontext():
            for groups, rec in ((self.groups, self.rec), (self.ghost_groups, self.ghost)):
                if rec is None:
                    continue
                j = max(0, min(int(k), len(rec["t_s"]) - 1))
                for group, p, m in zip(groups, rec["body_pos"][j], rec["body_mat"][j],
                                       strict=True):
                    group.move(*p.tolist()).rotate_R(m.tolist())
