"""run.lock names its owner by pid, start time, boot and host; only that live run is ever
signalled (a stale lock whose pid was reused killed an unrelated process)."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.errors import InputError
from evomotion.run.lock import (
    LOCK_NAME,
    RunLock,
    lock_owner,
    owner_state,
    parse_owner,
    process_start,
    signal_owner,
)


@pytest.fixture
def bystander():
    """A live process that has nothing to do with any run."""
    p = subprocess.Popen(["sleep", "60"])
    yield p
    p.kill()
    p.wait()


def _lock(d: Path, text: str) -> Path:
    d.mkdir(exist_ok=True)
    (d / LOCK_NAME).write_text(text)
    return d


def _json(pid, host=None, start=None, boot=None):
    return json.dumps({"pid": pid, "host": host or socket.gethostname(), "start": start,
                       "boot": boot, "command": "evomotion"})


def test_lock_records_pid_start_boot_host(tmp_path):
    with RunLock(tmp_path):
        owner = lock_owner(tmp_path)
        assert owner.pid == os.getpid() and owner.host == socket.gethostname()
        assert owner.start == process_start(os.getpid())
        assert owner_state(owner, tmp_path / LOCK_NAME) == "running"
    assert (tmp_path / LOCK_NAME).read_text() == ""
    assert owner_state(lock_owner(tmp_path)) == "none"


def _stale_locks(b: subprocess.Popen) -> dict[str, str]:
    real = process_start(b.pid)
    return {
        "reused pid, other start time": _json(b.pid, start=(real or 0) + 12345),
        "reused pid, older lock format": f"pid {b.pid} on {socket.gethostname()}\n",
        "reused pid, its real start time but not a run": _json(b.pid, start=real),
        "another host": _json(b.pid, host="remote-host", start=real),
        "another host, older format": f"pid {b.pid} on remote-host\n",
        "pid 0": _json(0, start=1),
        "pid 1": _json(1, start=1),
        "pid -1": f"pid -1 on {socket.gethostname()}",
        "30-digit pid": _json(10**30, start=1),
        "30-digit pid, older format": f"pid {10**30} on {socket.gethostname()}",
        "garbage": "\x00\xff{{{",
    }


def test_stale_locks_never_signal_a_bystander(tmp_path, bystander):
    assert process_start(bystander.pid) is not None
    for i, (case, text) in enumerate(_stale_locks(bystander).items()):
        d = _lock(tmp_path / f"r{i}", text)
        with pytest.raises(InputError) as e:
            signal_owner(d, signal.SIGTERM)
        assert "\n" not in str(e.value), case
        assert bystander.poll() is None, f"{case}: the bystander was signalled"
    time.sleep(0.2)
    assert bystander.poll() is None


def test_cli_stop_on_a_stale_lock(tmp_path, bystander):
    d = _lock(tmp_path / "r", _json(bystander.pid, start=process_start(bystander.pid) + 7))
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "stop", str(d)],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "stale lock" in r.stderr and "Traceback" not in r.stderr
    assert bystander.poll() is None


def test_states(tmp_path, bystander):
    real = process_start(bystander.pid)
    assert owner_state(parse_owner(_json(bystander.pid, start=real + 1))) == "stale"
    assert owner_state(parse_owner(_json(bystander.pid, host="elsewhere", start=real))) \
        == "remote"
    assert owner_state(parse_owner(_json(bystander.pid, start=real))) == "stale"
    gone = subprocess.Popen(["true"])
    gone.wait()
    assert owner_state(parse_owner(_json(gone.pid, start=1))) == "stale"
    assert parse_owner(_json(0)) is None and parse_owner(_json(10**30)) is None


def test_stop_signals_the_real_run(tmp_path):
    """A run started by the CLI is stopped (SIGTERM -> checkpoint, 'interrupted')."""
    out = tmp_path / "run"
    p = subprocess.Popen([sys.executable, "-m", "evomotion.cli", "run", "functions", "-q",
                          "--out", str(out), "--set", "run.generations=100000",
                          "--set", "run.checkpoint_every=1000"])
    try:
        stats = out / "stats.csv"
        for _ in range(400):  # the loop runs once a generation is in stats.csv (the file
            # itself is made in the set-up, where SIGTERM ends the run before its log line)
            if lock_owner(out) is not None and stats.exists() and \
                    stats.read_text().count("\n") >= 2:
                break
            time.sleep(0.05)
        assert owner_state(lock_owner(out), out / LOCK_NAME) == "running"
        assert signal_owner(out, signal.SIGTERM) == p.pid
        assert p.wait(timeout=60) == 130
    finally:
        p.kill()
    assert "stopped: interrupted" in (out / "log.txt").read_text()


@settings(max_examples=300, deadline=None)
@given(st.one_of(st.text(max_size=200), st.builds(
    lambda pid, host, start: json.dumps({"pid": pid, "host": host, "start": start}),
    st.one_of(st.integers(), st.floats(), st.text(max_size=5), st.none(), st.booleans()),
    st.one_of(st.text(max_size=300), st.integers(), st.none()),
    st.one_of(st.integers(), st.floats(), st.text(max_size=5), st.none()))))
def test_lock_text_fuzz(text):
    owner = parse_owner(text)
    if owner is not None:
        assert 1 < owner.pid <= 1 << 22 and isinstance(owner.host, str)
    assert owner_state(owner) in ("none", "running", "stale", "remote", "unknown")


def test_a_lock_file_that_is_a_link_is_refused_and_its_target_untouched(tmp_path):
    from evomotion.outfile import WriteError

    thesis = tmp_path / "thesis.tex"
    thesis.write_text("chapter 1\n")
    run = tmp_path / "run"
    run.mkdir()
    (run / LOCK_NAME).symlink_to(thesis)
    with pytest.raises(WriteError, match="found a link"):
        RunLock(run).acquire()
    assert thesis.read_text() == "chapter 1\n"


def test_non_ascii_digits_in_an_old_lock_are_no_pid():
    assert parse_owner("pid \u00b2 on host") is None
    assert parse_owner("pid \u0663\u0663 on host") is None
