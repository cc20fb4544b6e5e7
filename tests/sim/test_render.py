import numpy as np
import pytest

from evomotion.sim.render import RenderUnavailableError, render_video
from evomotion.sim.robots import nao


def test_render_video_writes_moving_frames(tmp_path):
    import imageio.v3 as iio

    model = nao.load_model()
    q0 = nao.initial_data(model).qpos.copy()
    qpos = np.tile(q0, (30, 1))
    qpos[:, 0] = np.linspace(0, 0.3, 30)  # torso slides forward; the camera follows
    qpos[:, nao.qpos_address(model, "HeadYaw")] = np.linspace(-1, 1, 30)
    try:
        out = render_video(qpos, 0.04, tmp_path / "v.mp4", fps=25, width=160, height=128)
    except RenderUnavailableError as exc:
        pytest.skip(f"no GL backend here: {exc}")
    frames = iio.imread(out)
    assert frames.shape[1:] == (128, 160, 3) and len(frames) >= 25
    assert np.abs(frames[0].astype(int) - frames[-1].astype(int)).mean() > 0.5
