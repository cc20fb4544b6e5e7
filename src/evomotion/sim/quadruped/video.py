"""An MP4 of a simulated plan execution, via :func:`evomotion.sim.render.render_video`.

The qpos trajectory of :func:`.execute.plan_qpos` is subsampled to one frame per
``speed / fps`` simulated seconds (``speed`` > 1 plays faster than real time) and rendered
in the renderer's child process from the model's MJCF, with the ``"overview"`` camera
(following the torso from above and behind) unless told otherwise.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from evomotion.sim.quadruped.execute import plan_qpos
from evomotion.sim.quadruped.model import QuadrupedSpec, model_xml
from evomotion.sim.render import render_video


def render_plan_video(states: list[dict], out_path: str | Path,
                      spec: QuadrupedSpec = QuadrupedSpec(), fps: int = 25,
                      speed: float = 1.0, width: int = 480, height: int = 352,
                      camera: str = "overview", qpos: np.ndarray | None = None,
                      xml: str | None = None, **execute_kwargs: float) -> Path:
    """Simulate ``states`` (keyword arguments as :func:`.execute.execute_plan`) and render
    the execution to ``out_path`` at ``fps`` frames per second, ``speed`` times real time.
    ``qpos`` (one row per ``spec.timestep``) skips the simulation; ``xml`` replaces the
    scene's MJCF (the same model with visual-only additions, e.g. a world's obstacles). Raises
    :class:`evomotion.sim.render.RenderUnavailableError` without an OpenGL backend."""
    if speed <= 0 or fps <= 0:
        raise ValueError("fps and speed must be positive")
    if qpos is None:
        qpos, _ = plan_qpos(states, spec, **execute_kwargs)
    if len(qpos) == 0:
        raise ValueError("nothing to render: the plan has no finite execution")
    stride = max(1, int(round(speed / (fps * spec.timestep))))
    frames = np.ascontiguousarray(qpos[::stride])
    return render_video(frames, 1.0 / fps, out_path, fps=fps, width=width, height=height,
                        model_xml=xml or model_xml(spec), camera=camera)
