"""A short video of a plan execution with the renderer's "overview" camera."""

import numpy as np
import pytest

from evomotion.sim.quadruped import QuadrupedSpec, plan_qpos
from evomotion.sim.quadruped.video import render_plan_video
from evomotion.sim.render import RenderUnavailableError


def test_render_plan_video_writes_frames(tmp_path) -> None:
    import imageio.v3 as iio

    spec = QuadrupedSpec()
    h = spec.hips_m()[:, :2] / spec.unit_m
    feet = (h + [[-1.5, 0], [-1.5, 0], [1.5, 0], [1.5, 0]]).tolist()
    moved = [list(f) for f in feet]
    moved[0] = [feet[0][0], feet[0][1] + 0.4]
    states = [{"body": [0.0, 0.0, 0.0], "feet": feet, "rule": 0},
              {"body": [0.0, 0.0, 0.0], "feet": moved, "rule": 4}]
    qpos, dt = plan_qpos(states, spec, settle_seconds=0.2, final_seconds=0.2)
    assert qpos.shape[1] == 19 and dt == spec.timestep
    try:
        out = render_plan_video(states, tmp_path / "walk.mp4", spec, fps=10, width=160,
                                height=128, qpos=qpos)
    except RenderUnavailableError as exc:
        pytest.skip(f"no GL backend here: {exc}")
    frames = iio.imread(out)
    assert frames.shape[1:] == (128, 160, 3) and len(frames) >= 8
    mid = frames[len(frames) // 2].astype(int)
    assert np.abs(frames[0].astype(int) - mid).mean() > 0.5  # the swinging leg shows
