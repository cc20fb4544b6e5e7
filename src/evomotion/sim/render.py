"""Offscreen rendering of a NAO trajectory to MP4 (MuJoCo ``Renderer`` + imageio-ffmpeg).

The GL backend comes from ``MUJOCO_GL`` (OSMesa or EGL, chosen in :mod:`evomotion.sim`),
which MuJoCo reads once, when it is first imported. Because any earlier ``import mujoco`` in
the process fixes the backend (and an OSMesa teardown can crash), frames are rendered in a
fresh child process (``python -m evomotion.sim.render``) that receives the trajectory on
stdin. Shadows are off (about 6x faster on llvmpipe); a camera follows the torso from the
robot's right side, and visual-only floor marks every 0.5 m along +x (a post every metre)
show the progress. Where no backend works, :class:`RenderUnavailableError` says so and callers
skip only the video.
"""

from __future__ import annotations

import contextlib
import contextvars
import io
import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.errors import InputError

UNAVAILABLE = "RENDER-UNAVAILABLE: "
RENDER_TIMEOUT_S = 600


class RenderUnavailableError(RuntimeError):
    """No working OpenGL backend for offscreen rendering."""


class RenderError(InputError, RuntimeError):
    """A video could not be made (the encoder failed, timed out or wrote a cut file): one
    line for the command line, never a traceback; no partial video is left."""


CAMERAS = ("follow", "kick", "overview")

#: why videos are off in this context (``run.videos = false``), or None
_VIDEOS_OFF: contextvars.ContextVar[str | None] = contextvars.ContextVar("videos_off",
                                                                         default=None)


@contextlib.contextmanager
def videos_off(reason: str | None) -> Iterator[None]:
    """Within the block, :func:`render_video` raises :class:`RenderUnavailableError` with
    ``reason`` instead of rendering (every caller then skips only its video and logs why);
    ``None`` leaves rendering on. The run loop uses it for ``run.videos = false``."""
    token = _VIDEOS_OFF.set(reason)
    try:
        yield
    finally:
        _VIDEOS_OFF.reset(token)


def check_videos_on() -> None:
    """Raise :class:`RenderUnavailableError` where :func:`videos_off` is in force (before
    the work of a video is done: its simulation, say)."""
    off = _VIDEOS_OFF.get()
    if off is not None:
        raise RenderUnavailableError(off)


def render_video(qpos: np.ndarray, dt: float, out_path: str | Path, fps: int = 25,
                 width: int = 480, height: int = 352, model_path: Path | None = None,
                 model_xml: str | None = None, camera: str = "follow",
                 assets: dict[str, bytes] | None = None, robot=None) -> Path:
    """Render ``qpos[T, nq]`` (one row per physics step of ``dt`` s) at ``fps`` to an MP4.

    The model: ``robot`` (any :class:`~evomotion.sim.robots.Robot`: its edited model and
    assets, the camera following its torso unless ``camera`` is given otherwise), else
    ``model_xml``, else the file ``model_path``, else the NAO's MJCF.
    ``model_xml`` (MJCF text) replaces the model file (a scene built in memory, such as the
    kick's NAO + ball, or a robot's ``Robot.xml``); ``assets``: the files it names (meshes,
    textures; by default those of the robot built from that text). ``camera``: ``"follow"``
    (the torso, from the robot's right) or ``"kick"`` (robot and ball both in view: the camera
    looks at their midpoint and backs off as the ball rolls away; needs a body named ``ball``)
    or ``"overview"`` (the torso from higher up and farther away, for a small robot walking in
    the plane, such as the quadruped of :mod:`evomotion.sim.quadruped`, about 0.6 m across)
    or ``"follow=BODY,DISTANCE_M,HEIGHT_M"`` (like ``"follow"`` for another robot: the camera
    follows ``BODY`` from ``DISTANCE_M`` away, looking at ``HEIGHT_M`` above the floor).

    ``out_path`` is checked before any work (:func:`evomotion.outfile.check_target`: an
    existing folder, not a device or FIFO); the encoder writes a temporary file next to it,
    renamed over ``out_path`` only when the whole video is written, so a failed or killed
    render leaves no partial MP4 there."""
    from evomotion.outfile import WriteError, atomic_output, check_target

    check_videos_on()
    if robot is not None:
        if not robot.xml:
            raise RuntimeError("the robot's edited model cannot be written as MJCF text")
        model_xml, assets = robot.xml, robot.assets if assets is None else assets
        if camera == "follow":
            from evomotion.sim.play import robot_camera

            camera = robot_camera(robot)
    if model_path is None:
        from evomotion.sim.robots.nao.model import MODEL_PATH

        model_path = MODEL_PATH
    out_path = check_target(out_path, "video")
    if camera not in CAMERAS and not camera.startswith("follow="):
        raise ValueError(f"unknown camera {camera!r}; available: {', '.join(CAMERAS)}")
    if assets is None and model_xml:
        from evomotion.sim.robots.mjcf import assets_for

        assets = assets_for(model_xml)
    assets = assets or {}
    buf = io.BytesIO()
    stride = max(1, int(round(1.0 / (fps * dt))))
    xml = np.frombuffer((model_xml or "").encode(), dtype=np.uint8)
    names = np.frombuffer(json.dumps(list(assets)).encode(), dtype=np.uint8)
    files: dict[str, Any] = {f"asset_{i}": np.frombuffer(data, dtype=np.uint8)
                             for i, data in enumerate(assets.values())}
    np.savez(buf, qpos=np.ascontiguousarray(qpos[::stride], dtype=np.float64), xml=xml,
             asset_names=names, **files)
    with atomic_output(out_path, "video", suffix=".tmp.mp4") as tmp:
        cmd = [sys.executable, "-m", "evomotion.sim.render", str(model_path), str(tmp),
               str(fps), str(width), str(height), camera]
        try:
            proc = subprocess.run(cmd, input=buf.getvalue(), capture_output=True,
                                  timeout=RENDER_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            raise RenderError(f"rendering {out_path} took more than {RENDER_TIMEOUT_S} s"
                               ) from None
        err = proc.stderr.decode(errors="replace")
        if proc.returncode != 0:
            if UNAVAILABLE in err:
                raise RenderUnavailableError(
                    err.split(UNAVAILABLE, 1)[1].strip().splitlines()[0])
            for text, why in _DISK_ERRORS:  # the encoder could not write: one line
                if text in err:
                    raise WriteError(f"{out_path}: cannot write the video ({why})")
            last = err.strip().splitlines()[-1] if err.strip() else f"exit {proc.returncode}"
            raise RenderError(f"rendering {out_path} failed: {last}")
        if not complete_mp4(tmp):  # the encoder may end "well" on a full disk
            try:
                full = os.statvfs(tmp.parent).f_bavail == 0
            except OSError:
                full = False
            if full:
                raise WriteError(f"{out_path}: cannot write the video (no space left on the "
                                 "device)")
            raise RenderError(f"rendering {out_path}: the encoder wrote an incomplete MP4")
    return out_path


def complete_mp4(path: Path) -> bool:
    """Whether ``path`` is a whole MP4: top-level boxes that add up to the file's size, with
    the ``moov`` index and the ``mdat`` data (a video cut short by a full disk is not)."""
    try:
        with open(path, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            pos, kinds = 0, set()
            while pos < size:
                fh.seek(pos)
                head = fh.read(16)
                if len(head) < 8:
                    return False
                n, kind = int.from_bytes(head[:4], "big"), head[4:8]
                if n == 1 and len(head) == 16:
                    n = int.from_bytes(head[8:16], "big")
                elif n == 0:
                    n = size - pos
                if n < 8:
                    return False
                kinds.add(kind)
                pos += n
    except OSError:
        return False
    return pos == size and {b"moov", b"mdat"} <= kinds


#: what the encoder (ffmpeg) prints when the disk refuses the video, and our reason
_DISK_ERRORS = (("No space left on device", "no space left on the device"),
                ("Disk quota exceeded", "disk quota exceeded"),
                ("Read-only file system", "read-only file system"),
                ("Permission denied", "permission denied"))

MARK_SPACING_M = 0.5  # floor marks across the +x direction: every 0.5 m, a post every 1 m
MARK_RANGE_M = (-2.0, 8.0)


def _with_distance_marks(model_path: str, xml: str = "", assets: dict | None = None):
    """The model with visual-only floor marks (no collisions, no mass): a line across the
    floor every 0.5 m along x, darker and with a post every metre, so a video shows progress
    while the camera follows the robot."""
    import mujoco

    spec = (mujoco.MjSpec.from_string(xml, assets=assets or None) if xml
            else mujoco.MjSpec.from_file(model_path))
    world = spec.worldbody
    lo, hi = MARK_RANGE_M
    for i, x in enumerate(np.arange(lo, hi + 1e-9, MARK_SPACING_M)):
        metre = abs(x - round(x)) < 1e-9
        rgba = [0.15, 0.25, 0.55, 1.0] if metre else [0.45, 0.5, 0.6, 1.0]
        world.add_geom(name=f"mark_{i}", type=mujoco.mjtGeom.mjGEOM_BOX,
                       size=[0.006 if metre else 0.004, 1.0, 0.0005],
                       pos=[float(x), 0.0, 0.0005], rgba=rgba, contype=0, conaffinity=0,
                       mass=0.0, density=0.0)
        if metre:
            world.add_geom(name=f"post_{i}", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                           size=[0.01, 0.06, 0.0], pos=[float(x), 0.45, 0.06], rgba=rgba,
                           contype=0, conaffinity=0, mass=0.0, density=0.0)
    return spec.compile()


def _render_frames(model_path: str, frames_q: np.ndarray, width: int, height: int,
                   camera: str = "follow", xml: str = "", assets: dict | None = None):
    """The frames of ``frames_q``, one at a time (a long video is never held in memory)."""
    import mujoco

    model = _with_distance_marks(model_path, xml, assets)
    data = mujoco.MjData(model)
    try:
        renderer = mujoco.Renderer(model, height=height, width=width)
    except Exception as exc:  # no GL context (no OSMesa/EGL)
        raise RenderUnavailableError(
            f"offscreen rendering unavailable ({exc}); install libosmesa6 "
            "(MUJOCO_GL=osmesa) or use EGL (MUJOCO_GL=egl)") from None
    return _frames(model, data, renderer, frames_q, camera)


def _torso_body(model) -> int:
    """The body the cameras follow: the body ``torso``, else (a robot whose torso has another
    name, such as the OP3's ``body``) the body of the model's first free joint."""
    import mujoco

    try:
        return int(model.body("torso").id)
    except KeyError:
        free = np.flatnonzero(model.jnt_type == mujoco.mjtJoint.mjJNT_FREE)
        return int(model.jnt_bodyid[free[0]]) if free.size else 0


def _frames(model, data, renderer, frames_q: np.ndarray, camera: str):
    import mujoco

    cam = mujoco.MjvCamera()
    cam.distance, cam.azimuth, cam.elevation = 1.1, -70.0, -12.0
    torso_id = _torso_body(model)
    try:
        for q in frames_q:
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)
            torso = data.xpos[torso_id]
            if camera == "kick":
                ball = data.body("ball").xpos
                mid = 0.5 * (torso[:2] + ball[:2])
                cam.lookat[:] = [mid[0], mid[1], 0.18]
                cam.distance = 1.3 + 0.7 * float(np.linalg.norm(ball[:2] - torso[:2]))
                cam.azimuth, cam.elevation = -75.0, -15.0
            elif camera == "overview":
                cam.lookat[:] = [torso[0], torso[1], 0.05]
                cam.distance, cam.azimuth, cam.elevation = 1.6, -60.0, -45.0
            elif camera.startswith("follow="):
                body, dist, height = camera.split("=", 1)[1].split(",")
                cam.lookat[:] = data.body(body).xpos
                cam.lookat[2] = float(height)
                cam.distance = float(dist)
            else:
                cam.lookat[:] = torso
                cam.lookat[2] = 0.2
            renderer.update_scene(data, camera=cam)
            renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
            yield renderer.render()
    finally:
        renderer.close()


def main(argv: list[str]) -> int:
    """The child process: the trajectory (and model text, assets) on stdin, the MP4 written
    to the path given (the parent's temporary file), frame by frame."""
    import evomotion.sim  # noqa: F401  (chooses MUJOCO_GL before mujoco is imported)

    model_path, out_path, fps, width, height, camera = argv
    data = np.load(io.BytesIO(sys.stdin.buffer.read()), allow_pickle=False)
    frames_q, xml = data["qpos"], data["xml"].tobytes().decode()
    names = json.loads(data["asset_names"].tobytes().decode()) if "asset_names" in data else []
    assets = {name: data[f"asset_{i}"].tobytes() for i, name in enumerate(names)}
    try:
        frames = _render_frames(model_path, frames_q, int(width), int(height), camera, xml,
                                assets)
    except RenderUnavailableError as exc:
        print(f"{UNAVAILABLE}{exc}", file=sys.stderr)
        return 3
    import imageio.v2 as iio

    with iio.get_writer(out_path, format="FFMPEG", fps=int(fps), codec="libx264") as writer:
        for frame in frames:
            writer.append_data(frame)  # type: ignore[attr-defined]  # not in the stub
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
