"""The one atomic writer (evomotion.outfile): what it refuses, what a failed write leaves."""

from __future__ import annotations

import errno
import os
import socket
import stat
import subprocess
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion import outfile
from evomotion.outfile import (
    RUN_MARKER,
    WriteError,
    append_text,
    atomic_output,
    atomic_write_bytes,
    check_target,
    claim,
    open_append,
    read_marker,
    truncate_file,
    write_marker,
)


def _no_temporaries(folder):
    return [p.name for p in folder.iterdir() if p.name.endswith(".tmp")] == []


def test_new_file_and_replace(tmp_path):
    p = tmp_path / "a.txt"
    atomic_write_bytes(p, b"one")
    atomic_write_bytes(p, b"two")
    assert p.read_bytes() == b"two" and _no_temporaries(tmp_path)


def test_device_nodes_are_never_replaced():
    """As root, writing to /dev/null used to replace the device by a regular file."""
    for dev in ("/dev/null", "/dev/zero", "/dev/full"):
        if not os.path.exists(dev):
            continue
        before = os.stat(dev)
        with pytest.raises(WriteError, match="found a character device"):
            atomic_write_bytes(dev, b"x", "NAOqi script")
        after = os.stat(dev)
        assert stat.S_ISCHR(after.st_mode) and after.st_rdev == before.st_rdev


def test_fifo_socket_folder_and_links_to_them_are_refused(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    sock_path = tmp_path / "sock"
    s = socket.socket(socket.AF_UNIX)
    s.bind(str(sock_path))
    link = tmp_path / "link"
    link.symlink_to("/dev/null")
    try:
        for target, kind in ((fifo, "FIFO"), (sock_path, "socket"), (tmp_path, "folder"),
                             (link, "character device")):
            with pytest.raises(WriteError, match=f"found a {kind}"):
                atomic_write_bytes(target, b"x")
        assert stat.S_ISFIFO(os.stat(fifo).st_mode) and link.is_symlink()
    finally:
        s.close()
    assert _no_temporaries(tmp_path)


def test_missing_folder_is_refused_unless_asked_to_make_it(tmp_path):
    with pytest.raises(WriteError, match="does not exist"):
        check_target(tmp_path / "no" / "such" / "plan.json", "plan")
    assert not (tmp_path / "no").exists()
    atomic_write_bytes(tmp_path / "made" / "f", b"x", mkdir=True)
    assert (tmp_path / "made" / "f").read_bytes() == b"x"


@pytest.mark.parametrize("code,text", [(errno.ENOSPC, "no space left on the device"),
                                       (errno.EROFS, "read-only file system"),
                                       (errno.EACCES, "permission denied")])
def test_os_errors_are_one_line_and_leave_nothing(tmp_path, monkeypatch, code, text):
    p = tmp_path / "best.json"
    p.write_bytes(b"old")

    def fail(*a, **k):
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(outfile.os, "replace", fail)
    with pytest.raises(WriteError) as e:
        atomic_write_bytes(p, b"new", "best record")
    assert str(e.value) == f"{p}: cannot write the best record ({text})"
    assert p.read_bytes() == b"old" and _no_temporaries(tmp_path)


def test_a_failing_writer_leaves_no_partial_file(tmp_path):
    p = tmp_path / "video.mp4"
    with pytest.raises(RuntimeError), atomic_output(p, "video", suffix=".tmp.mp4") as tmp:
        tmp.write_bytes(b"half a video")
        raise RuntimeError("encoder died")
    assert not p.exists() and _no_temporaries(tmp_path)


def _tmpfs(path, opts):
    path.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", opts, "tmpfs", str(path)],
                       capture_output=True)
    if r.returncode != 0:
        pytest.skip("cannot mount a tmpfs here (needs root and CAP_SYS_ADMIN)")
    return path


def test_a_really_full_disk(tmp_path):
    disk = _tmpfs(tmp_path / "disk", "size=64k")
    try:
        (disk / "f").write_bytes(b"kept")
        with pytest.raises(WriteError, match="no space left on the device"):
            atomic_write_bytes(disk / "f", os.urandom(256 * 1024))
        assert (disk / "f").read_bytes() == b"kept" and _no_temporaries(disk)
        with pytest.raises(WriteError, match="no space left on the device"):
            append_text(disk / "log.txt", "x" * (256 * 1024), "run log")
    finally:
        subprocess.run(["umount", str(disk)], check=False)


def test_a_really_read_only_disk(tmp_path):
    disk = _tmpfs(tmp_path / "ro", "size=64k,ro")
    try:
        with pytest.raises(WriteError, match="read-only file system"):
            atomic_write_bytes(disk / "f", b"x")
    finally:
        subprocess.run(["umount", str(disk)], check=False)


def test_open_append_refuses_a_fifo_without_blocking(tmp_path):
    fifo = tmp_path / "log.txt"
    os.mkfifo(fifo)
    with pytest.raises(WriteError, match="FIFO"):
        open_append(fifo, "run log")


def test_truncate_never_pads(tmp_path):
    """A file cut short by hand was padded with zeros up to the checkpoint's offset."""
    p = tmp_path / "population.bin"
    p.write_bytes(b"")
    truncate_file(p, 179440)
    assert p.read_bytes() == b""
    p.write_bytes(b"abcdef")
    truncate_file(p, 3)
    assert p.read_bytes() == b"abc"


def test_writes_inside_a_run_folder_are_claimed(tmp_path):
    write_marker(tmp_path, "functions", ["config.toml"])
    atomic_write_bytes(tmp_path / "plots" / "a.png", b"x", mkdir=True)
    atomic_write_bytes(tmp_path / "best.motion", b"x")
    assert set(read_marker(tmp_path)["files"]) == {"config.toml", "plots", "best.motion"}
    other = tmp_path.parent / f"{tmp_path.name}-elsewhere"
    other.mkdir()
    claim(other / "x")  # outside any run folder: nothing happens
    assert not (other / RUN_MARKER).exists()


@settings(max_examples=150, deadline=None)
@given(st.binary(max_size=300))
def test_marker_reader_never_raises(tmp_path_factory, data):
    d = tmp_path_factory.mktemp("m")
    (d / RUN_MARKER).write_bytes(data)
    doc = read_marker(d)
    assert doc is None or isinstance(doc["files"], list)


def test_cli_turns_a_stray_oserror_into_one_line(tmp_path):
    code = ("import sys; from evomotion import cli; import typer\n"
            "@cli.app.command('boom')\n"
            "def boom():\n"
            "    raise OSError(28, 'No space left on device', 'x.bin')\n"
            "cli.main(['evomotion', 'boom'])\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       cwd=tmp_path)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert r.stderr.strip() == "error: x.bin: no space left on the device"


def test_modes_are_those_open_would_give(tmp_path):
    """mkstemp's 0600 used to stick to every file written (exports, plots, replaced files)."""
    p = tmp_path / "script.py"
    atomic_write_bytes(p, b"x")
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(os.stat(p).st_mode) == 0o666 & ~umask
    p.chmod(0o755)
    atomic_write_bytes(p, b"y")
    assert stat.S_IMODE(os.stat(p).st_mode) == 0o755


def test_a_long_name_can_be_written(tmp_path):
    p = tmp_path / ("n" * 250)
    atomic_write_bytes(p, b"x")
    assert p.read_bytes() == b"x"


def test_a_write_into_a_users_subfolder_claims_nothing(tmp_path):
    """`plot --out RUN/analysis/fit` marked the user's analysis/ as the run's."""
    write_marker(tmp_path, "functions", ["config.toml"])
    (tmp_path / "analysis").mkdir()
    atomic_write_bytes(tmp_path / "analysis" / "fit.png", b"x")
    atomic_write_bytes(tmp_path / "made" / "a.png", b"x", mkdir=True)
    assert set(read_marker(tmp_path)["files"]) == {"config.toml", "made"}


def test_a_folder_made_by_a_write_killed_before_its_claim_is_still_the_runs(tmp_path):
    """humanoid-balance's naoqi/: a kill after the folder's first file was written but before
    the claim left naoqi/ existing and unclaimed, and the resume (the folder now there) never
    claimed it, so the marker differed from an uninterrupted run's."""
    write_marker(tmp_path, "functions", ["config.toml"])

    def killed(event, path):
        if event == "written":
            raise KeyboardInterrupt  # stands for the kill: the file is complete, not renamed

    outfile.WRITE_HOOKS.append(killed)
    try:
        with pytest.raises(KeyboardInterrupt):
            atomic_write_bytes(tmp_path / "naoqi" / "policy.json", b"x", mkdir=True)
    finally:
        outfile.WRITE_HOOKS.remove(killed)
    assert (tmp_path / "naoqi").is_dir()
    atomic_write_bytes(tmp_path / "naoqi" / "policy.json", b"x", mkdir=True)  # the resume
    assert set(read_marker(tmp_path)["files"]) == {"config.toml", "naoqi"}
