"""Offscreen rendering of a NAO trajectory to MP4 (MuJoCo ``Renderer`` + imageio-ffmpeg).

The GL backend comes from ``MUJOCO_GL`` (``osmesa`` by default, see :mod:`evomotion.sim`;
``egl`` on GPU machines). Shadows are switched off (about 6x faster on llvmpipe). A camera
follows the torso from the robot's right side. Where no backend works,
:class:`RenderUnavailableError` says so and callers skip only the video.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np


class RenderUnavailableError(RuntimeError):
    """No working OpenGL backend for offscreen rendering."""


def _camera(model: mujoco.MjModel, data: mujoco.MjData) -> mujoco.MjvCamera:
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = data.body("torso").xpos
    cam.lookat[2] = 0.2
    cam.distance, cam.azimuth, cam.elevation = 1.1, -70.0, -12.0
    return cam


def render_video(model: mujoco.MjModel, qpos: np.ndarray, dt: float, out_path: str | Path,
                 fps: int = 25, width: int = 480, height: int = 352) -> Path:
    """Render ``qpos[T, nq]`` (one row per physics step of ``dt`` s) at ``fps`` to ``out_path``."""
    import imageio.v3 as iio

    out_path = Path(out_path)
    stride = max(1, int(round(1.0 / (fps * dt))))
    frames_q = qpos[::stride]
    data = mujoco.MjData(model)
    try:
        renderer = mujoco.Renderer(model, height=height, width=width)
    except Exception as exc:  # no GL context (no OSMesa/EGL): report clearly
        raise RenderUnavailableError(f"offscreen rendering unavailable ({exc}); "
                                "install libosmesa6 or set MUJOCO_GL=egl") from None
    frames = []
    try:
        for q in frames_q:
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)
            renderer.update_scene(data, camera=_camera(model, data))
            renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
            frames.append(renderer.render().copy())
    finally:
        renderer.close()
    iio.imwrite(out_path, np.stack(frames), fps=fps, codec="libx264")
    return out_path
