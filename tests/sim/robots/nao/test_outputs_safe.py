"""Outputs of the NAO tools (issue 31): exports, motion files and replay videos go through the
one atomic writer; a device, FIFO or folder at an output path is refused and left alone, a
missing folder is refused before the work starts, a failed write leaves no partial file."""

from __future__ import annotations

import os
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from evomotion import outfile
from evomotion.errors import InputError
from evomotion.outfile import WriteError
from evomotion.sim.motion import Motion, format_motion, read_motion, write_motion
from evomotion.sim.robots.nao.export import export_motion, write_run_exports


def motion() -> Motion:
    """A small NAO motion inside the real robot's ranges and speeds (its own fixture)."""
    return Motion(("HeadYaw", "LKneePitch"), [0, 400, 800],
                  np.array([[0.0, 0.5], [0.2, 0.6], [0.0, 0.5]]))


def fifo(tmp_path: Path, name: str) -> Path:
    path = tmp_path / name
    os.mkfifo(path)
    return path


def is_fifo(path: Path) -> bool:
    return stat.S_ISFIFO(os.lstat(path).st_mode)


def within(seconds: float, fn, *args, **kwargs) -> BaseException | None:
    """The exception ``fn(*args, **kwargs)`` raised (``None``: none), asserting that it
    returned within ``seconds`` (a write into a FIFO would block)."""
    import threading

    out: dict = {}

    def call():
        try:
            fn(*args, **kwargs)
        except BaseException as e:  # noqa: BLE001 - returned to the test
            out["e"] = e

    t = threading.Thread(target=call, daemon=True)
    t.start()
    t.join(seconds)
    assert not t.is_alive(), f"{fn.__name__} blocked"
    return out.get("e")


@pytest.mark.parametrize("option", ["naoqi", "json_path"])
def test_export_to_a_fifo_is_refused_and_leaves_it(tmp_path, option):
    target = fifo(tmp_path, "out")
    e = within(10, export_motion, motion(), **{option: target})
    assert isinstance(e, WriteError) and "found a FIFO" in str(e), e
    assert is_fifo(target)


def test_export_through_a_link_to_a_fifo_is_refused(tmp_path):
    target = fifo(tmp_path, "pipe")
    (tmp_path / "link.py").symlink_to(target)
    e = within(10, export_motion, motion(), naoqi=tmp_path / "link.py")
    assert isinstance(e, WriteError) and "found a FIFO" in str(e), e
    assert is_fifo(target) and (tmp_path / "link.py").is_symlink()


def test_export_checks_every_output_before_writing_any(tmp_path):
    target = fifo(tmp_path, "k.json")
    with pytest.raises(WriteError):
        export_motion(motion(), naoqi=tmp_path / "ok.py", json_path=target)
    assert not (tmp_path / "ok.py").exists()


def test_export_cli_device_target_is_one_line_and_untouched(tmp_path):
    src = tmp_path / "m.motion"
    src.write_text(format_motion(motion()))
    target = fifo(tmp_path, "out.py")
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "export", str(src), "--naoqi",
                        str(target)], capture_output=True, text=True, timeout=60)
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode != 0 and len(lines) == 1 and lines[0].startswith("error: "), r.stderr
    assert "FIFO" in lines[0] and is_fifo(target)


def test_export_writes_atomically(tmp_path):
    """A write that fails after the temporary file is complete leaves the old file and no
    temporary one."""
    out = tmp_path / "k.json"
    out.write_text("old")

    def fail(event, path):
        if event == "written":
            raise OSError(28, "No space left on device")

    outfile.WRITE_HOOKS.append(fail)
    try:
        with pytest.raises(WriteError, match="no space left"):
            export_motion(motion(), json_path=out)
    finally:
        outfile.WRITE_HOOKS.remove(fail)
    assert out.read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == ["k.json"]


def test_run_exports_raise_write_errors_and_leave_devices(tmp_path):
    """A full disk ends the run unfinished (resumable) instead of a log line; a stale export
    that is not a regular file is never removed."""
    logged: list[str] = []
    fifo(tmp_path, "best_keyframes.json")
    with pytest.raises(WriteError):
        write_run_exports(motion(), tmp_path, logged.append)
    assert is_fifo(tmp_path / "best_keyframes.json")
    assert is_fifo(tmp_path / "best_keyframes.json") and not logged
    run = tmp_path / "run"
    run.mkdir()
    assert write_run_exports(motion(), run, logged.append) is True
    bad = Motion(("HeadYaw",), [0, 40], np.array([[0.0], [3.0]]))  # too fast: not exported
    assert write_run_exports(bad, run, logged.append) is False
    assert "not written" in logged[-1] and not list(run.iterdir())  # the stale ones removed


def test_write_motion_is_atomic_and_refuses_devices(tmp_path):
    target = fifo(tmp_path, "m.motion")
    e = within(10, write_motion, target, motion())
    assert isinstance(e, WriteError) and "found a FIFO" in str(e), e
    assert is_fifo(target)
    with pytest.raises(WriteError, match="does not exist"):
        write_motion(tmp_path / "no" / "m.motion", motion())
    out = write_motion(tmp_path / "ok.motion", motion())
    assert read_motion(out).values.tolist() == motion().values.tolist()


def test_read_motion_refuses_fifos_huge_files_and_huge_times(tmp_path):
    import threading

    pipe = fifo(tmp_path, "p.motion")
    out: dict = {}

    def read():
        try:
            read_motion(pipe)
        except InputError as e:
            out["e"] = str(e)

    t = threading.Thread(target=read, daemon=True)
    t.start()
    t.join(10)
    assert not t.is_alive() and "got a FIFO" in out.get("e", "")
    big = tmp_path / "big.motion"
    with open(big, "wb") as f:
        f.truncate(2**40)
    with pytest.raises(InputError, match="at most 8 MiB"):
        read_motion(big)
    late = tmp_path / "late.motion"
    late.write_text("#WEBOTS_MOTION,V1.0,HeadYaw\n99999999999999999999:00:000,P,0\n")
    with pytest.raises(InputError, match="late.motion:2: expected a time stamp of at most"):
        read_motion(late)


def test_replay_checks_the_video_path_before_simulating(tmp_path, monkeypatch):
    from evomotion.sim.robots.nao import replay

    src = tmp_path / "m.motion"
    src.write_text(format_motion(motion()))

    def never(*a, **k):
        raise AssertionError("simulated before the video path was checked")

    monkeypatch.setattr(replay, "simulate_motion", never)
    monkeypatch.setattr(replay, "stress_motion", never)
    for video, fragment in ((tmp_path / "none" / "v.mp4", "does not exist"),
                            (fifo(tmp_path, "v.mp4"), "found a FIFO"),
                            (tmp_path, "found a folder")):
        with pytest.raises(WriteError, match=fragment):
            replay.replay_command(src, video=video)
        with pytest.raises(WriteError, match=fragment):
            replay.replay_motion(motion(), video)
    assert is_fifo(tmp_path / "v.mp4")


def test_replay_cli_missing_video_folder_is_one_line_and_fast(tmp_path):
    src = tmp_path / "m.motion"
    src.write_text(format_motion(motion()))
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "replay", str(src), "--video",
                        str(tmp_path / "none" / "v.mp4")], capture_output=True, text=True,
                       timeout=60)
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode != 0 and len(lines) == 1 and "does not exist" in lines[0], r.stderr
    assert "Traceback" not in r.stderr and r.stdout == ""
