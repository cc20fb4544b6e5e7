"""Videos (issue 31): the target is checked before any work, the encoder writes a temporary
file that is renamed only when the video is complete, so a failed or killed render leaves no
partial MP4 (and an earlier video stays as it was)."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from evomotion.outfile import WriteError
from evomotion.sim import render

QPOS = np.zeros((4, 29))


def fake_run(returncode: int, stderr: bytes = b"", partial: bytes = b"\0\0\0 ftypisom"):
    """A stand-in for the render child: writes ``partial`` to the path it is given, then
    exits with ``returncode`` (-9: killed)."""
    calls: list[list[str]] = []

    def run(cmd, **kwargs):
        calls.append(cmd)
        if Path(cmd[4]).exists() and not Path(cmd[4]).is_file():
            raise AssertionError(f"the encoder was given {cmd[4]}, not a regular file")
        Path(cmd[4]).write_bytes(partial)
        return subprocess.CompletedProcess(cmd, returncode, b"", stderr)

    return run, calls


def names(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


@pytest.mark.parametrize("target,fragment", [
    ("none/v.mp4", "does not exist"), (".", "found a folder"), ("pipe.mp4", "found a FIFO"),
])
def test_the_target_is_checked_before_any_work(tmp_path, monkeypatch, target, fragment):
    os.mkfifo(tmp_path / "pipe.mp4")
    run, calls = fake_run(0)
    monkeypatch.setattr(subprocess, "run", run)
    with pytest.raises(WriteError, match=fragment):
        render.render_video(QPOS, 0.04, tmp_path / target)
    assert not calls


@pytest.mark.parametrize("returncode,stderr,error", [
    (-9, b"", RuntimeError),  # killed
    (1, b"Traceback\nValueError: boom", RuntimeError),
    (3, render.UNAVAILABLE.encode() + b"no GL here", render.RenderUnavailableError),
])
def test_a_failed_render_leaves_no_partial_video(tmp_path, monkeypatch, returncode, stderr,
                                                 error):
    run, calls = fake_run(returncode, stderr)
    monkeypatch.setattr(subprocess, "run", run)
    with pytest.raises(error):
        render.render_video(QPOS, 0.04, tmp_path / "v.mp4")
    assert names(tmp_path) == [] and calls
    assert Path(calls[0][4]).parent == tmp_path and calls[0][4].endswith(".tmp.mp4")
    (tmp_path / "v.mp4").write_bytes(b"old video")
    with pytest.raises(error):
        render.render_video(QPOS, 0.04, tmp_path / "v.mp4")
    assert names(tmp_path) == ["v.mp4"] and (tmp_path / "v.mp4").read_bytes() == b"old video"


def test_a_timeout_is_one_error_and_leaves_nothing(tmp_path, monkeypatch):
    def run(cmd, **kwargs):
        Path(cmd[4]).write_bytes(b"partial")
        raise subprocess.TimeoutExpired(cmd, kwargs.get("timeout"))

    monkeypatch.setattr(subprocess, "run", run)
    with pytest.raises(RuntimeError, match="took more than"):
        render.render_video(QPOS, 0.04, tmp_path / "v.mp4")
    assert names(tmp_path) == []


def test_a_successful_render_is_renamed_into_place(tmp_path, monkeypatch):
    run, calls = fake_run(0, partial=WHOLE_MP4)
    monkeypatch.setattr(subprocess, "run", run)
    out = render.render_video(QPOS, 0.04, tmp_path / "v.mp4")
    assert out == tmp_path / "v.mp4" and out.read_bytes() == WHOLE_MP4
    assert names(tmp_path) == ["v.mp4"]


def _box(kind: bytes, body: bytes) -> bytes:
    return (8 + len(body)).to_bytes(4, "big") + kind + body


#: the box structure of an MP4 (ftyp, mdat, moov), enough for the completeness check
WHOLE_MP4 = _box(b"ftyp", b"isom") + _box(b"mdat", b"frames") + _box(b"moov", b"index")


def test_an_encoder_that_exits_0_with_a_cut_video_leaves_nothing(tmp_path, monkeypatch):
    """On a full disk the encoder may end well and leave a 4096-byte file: never renamed."""
    run, calls = fake_run(0, partial=WHOLE_MP4[:-3])
    monkeypatch.setattr(subprocess, "run", run)
    with pytest.raises(RuntimeError, match="incomplete MP4"):
        render.render_video(QPOS, 0.04, tmp_path / "v.mp4")
    assert names(tmp_path) == []


def test_videos_off_still_skips_before_the_target_check(tmp_path):
    with render.videos_off("run.videos = false"), pytest.raises(render.RenderUnavailableError):
        render.render_video(QPOS, 0.04, tmp_path / "none" / "v.mp4")


def test_a_full_disk_during_encoding_is_one_line(tmp_path):
    """The encoder's 'No space left on device' was a RuntimeError traceback (replay --video)."""
    import subprocess as sp

    import numpy as np

    from evomotion.outfile import WriteError
    from evomotion.sim.render import RenderUnavailableError, render_video

    disk = tmp_path / "disk"
    disk.mkdir()
    if sp.run(["mount", "-t", "tmpfs", "-o", "size=4k", "tmpfs", str(disk)],
              capture_output=True).returncode != 0:
        pytest.skip("cannot mount a tmpfs here (needs root and CAP_SYS_ADMIN)")
    try:
        from evomotion.sim.robots.nao.model import MODEL_PATH, load_model

        q = np.tile(load_model().qpos0, (200, 1))
        try:
            with pytest.raises(WriteError, match="no space left on the device"):
                render_video(q, 0.02, disk / "v.mp4", model_path=MODEL_PATH)
        except RenderUnavailableError:
            pytest.skip("no offscreen rendering here")
        assert list(disk.iterdir()) == []
    finally:
        sp.run(["umount", "-l", str(disk)], check=False)
