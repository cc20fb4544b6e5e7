"""The studio's stop and resume never signal a process that is not the run (issue 31): a stale
lock whose pid was reused, another host's lock, pid 0 or 1, a 30-digit pid or garbage in
``run.lock``; and runs started from the studio are marked run folders the run loop accepts."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import time

import pytest
from hostile_helpers import finished_run as fake_run
from hostile_helpers import json_lock, stale_locks
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from evomotion.errors import InputError
from evomotion.outfile import RUN_MARKER, read_marker
from evomotion.run.folder import foreign_entries
from evomotion.studio import actions, data

FN = ["problem.dim=4", "algorithm.pop_size=10"]


@pytest.fixture
def sleeper():
    """A live process that has nothing to do with any run."""
    p = subprocess.Popen(["sleep", "30"])
    yield p
    p.kill()
    p.wait()


@pytest.fixture
def no_signals(monkeypatch):
    """Every signal the studio could send, recorded instead of sent."""
    sent: list = []
    monkeypatch.setattr(os, "kill", lambda *a: sent.append(("kill", a)))
    monkeypatch.setattr(os, "killpg", lambda *a: sent.append(("killpg", a)))
    monkeypatch.setattr(signal, "pidfd_send_signal", lambda *a: sent.append(("pidfd", a)),
                        raising=False)
    return sent


def test_stop_never_signals_an_unrelated_process(tmp_path, sleeper):
    d = fake_run(tmp_path)
    for kind, text in stale_locks(sleeper.pid).items():
        (d / "run.lock").write_text(text)
        status, detail, pid = data.run_status(d)
        assert pid is None, kind
        if kind.startswith("other-host"):
            assert status == "remote" and "another-host.example" in detail, kind
        else:
            assert status == "stale" and "stale" in detail, kind
        assert f"pid {sleeper.pid}" in detail and "\n" not in detail, kind
        with pytest.raises(InputError) as e:
            actions.stop_run(tmp_path, "r")
        msg = str(e.value)
        assert "\n" not in msg and ("no signal" in msg or "another host" in msg), (kind, msg)
        time.sleep(0.05)
        assert sleeper.poll() is None, f"{kind}: the unrelated process was signalled"
        row = data.summarize(tmp_path, d)
        assert row.pid is None and row.resumable == (status == "stale"), kind


@pytest.mark.parametrize("text", [
    "pid 0 on HOST", "pid 1 on HOST", "pid -1 on HOST",
    "pid 123456789012345678901234567890 on HOST",
    '{"pid": 0, "host": "HOST"}', '{"pid": 1, "host": "HOST", "start": 1}',
    '{"pid": -1, "host": "HOST"}', '{"pid": 123456789012345678901234567890, "host": "HOST"}',
    '{"pid": 1e30, "host": "HOST"}', '{"pid": true, "host": "HOST"}',
    '{"pid": "PID", "host": "HOST"}', '{"pid": PID, "host": "HO\\nST", "start": 5}',
    '{"pid": PID, "host": "HOST", "start": 1e400}', "[" * 5000, "\xff\xfe garbage \0",
    "pid PID on", "pid PID on HOST extra words", "",
], ids=lambda t: ascii(t)[:40])
def test_no_lock_text_signals_anyone_or_crashes(tmp_path, no_signals, text):
    text = text.replace("HOST", socket.gethostname()).replace("PID", str(os.getpid()))
    d = fake_run(tmp_path)
    (d / "run.lock").write_text(text, errors="surrogateescape")
    status, detail, pid = data.run_status(d)
    assert status in data.STATUSES and pid is None and "\n" not in detail
    (row,) = data.list_runs(tmp_path)
    json.dumps(row.row(), allow_nan=False)
    with pytest.raises(InputError) as e:
        actions.stop_run(tmp_path, "r")
    assert "\n" not in str(e.value)
    assert no_signals == []


@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(raw=st.one_of(
    st.binary(max_size=300),
    st.builds(lambda pid, host, start, boot: json.dumps(
        {"pid": pid, "host": host, "start": start, "boot": boot}).encode(),
        st.one_of(st.integers(), st.floats(), st.text(max_size=5), st.none(), st.booleans()),
        st.one_of(st.just(socket.gethostname()), st.text(max_size=20), st.integers()),
        st.one_of(st.integers(), st.none(), st.floats()), st.one_of(st.text(max_size=40),
                                                                     st.none())),
    st.builds(lambda pid, host: f"pid {pid} on {host}".encode(),
              st.integers(-10, 10**40), st.one_of(st.just(socket.gethostname()),
                                                    st.text(max_size=20)))))
def test_fuzzed_lock_text_through_status_and_stop(tmp_path_factory, no_signals, raw):
    root = tmp_path_factory.mktemp("fz")
    d = fake_run(root)
    (d / "run.lock").write_bytes(raw)
    status, detail, pid = data.run_status(d)
    assert status in data.STATUSES and "\n" not in detail
    for r in data.list_runs(root):
        json.dumps(r.row(), allow_nan=False)
    try:
        actions.stop_run(root, "r")
    except InputError as e:
        assert "\n" not in str(e)
    assert no_signals == []


def _wait(cond, timeout=60.0, what="condition"):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return
        time.sleep(0.1)
    raise AssertionError(f"timed out waiting for {what}")


def _rows(run_dir) -> int:
    return (run_dir / "stats.csv").read_bytes().count(b"\n")


def test_start_stop_and_resume_from_the_studio(tmp_path):
    """A run started by the studio is a marked run folder that the run loop accepts (its
    studio-stderr.txt named in the marker); stop signals that run and only it; resume appends
    to studio-stderr.txt and records it as the run's."""
    procs = []
    try:
        out, proc = actions.start_run(tmp_path, "functions", None,
                                      [*FN, "run.generations=3"])
        procs.append(proc)
        assert proc.wait(60) == 0, (out / actions.STDERR_NAME).read_text()
        assert data.run_status(out)[:2] == ("finished", "generations")
        marker = read_marker(out)
        assert marker["study"] == "functions" and actions.STDERR_NAME in marker["files"]
        assert foreign_entries(out) == []

        out, proc = actions.start_run(tmp_path, "functions", None,
                                      [*FN, "run.generations=10000000"])
        procs.append(proc)
        _wait(lambda: data.run_status(out)[0] == "running", what="the run to lock its folder")
        assert data.run_status(out)[2] == proc.pid
        _wait(lambda: _rows(out) > 2, what="the run's loop")  # SIGTERM is its Ctrl-C there
        assert actions.stop_run(tmp_path, out.name) == proc.pid
        assert proc.wait(60) == 130, (out / actions.STDERR_NAME).read_text()[-2000:]
        status, reason, _ = data.run_status(out)
        assert (status, reason) == ("interrupted", "interrupted")
        assert data.is_resumable(out, status)

        (out / actions.STDERR_NAME).unlink()  # resume recreates it and claims it again
        marker = read_marker(out)
        marker["files"].remove(actions.STDERR_NAME)
        (out / RUN_MARKER).write_text(json.dumps(marker))
        rows = _rows(out)
        proc = actions.resume_run(tmp_path, out.name)
        procs.append(proc)
        assert actions.STDERR_NAME in read_marker(out)["files"]
        _wait(lambda: data.run_status(out)[0] == "running", what="the resumed run")
        _wait(lambda: _rows(out) > rows, what="the resumed run's loop")
        assert actions.stop_run(tmp_path, out.name) == proc.pid
        assert proc.wait(60) == 130, (out / actions.STDERR_NAME).read_text()[-2000:]
        assert foreign_entries(out) == []
        with pytest.raises(InputError, match="not running"):
            actions.stop_run(tmp_path, out.name)
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
                p.wait()


def test_a_run_that_fails_to_start_reports_its_last_stderr_line(tmp_path, monkeypatch):
    monkeypatch.setattr(actions, "run_command",
                        lambda *a: ["run", "no-such-study", "--out", str(a[-1])])
    with pytest.raises(InputError) as e:
        actions.start_run(tmp_path, "functions", None, FN)
    assert "\n" not in str(e.value) and "no-such-study" in str(e.value)


def test_resume_refuses_a_running_or_finished_run(tmp_path, sleeper):
    d = fake_run(tmp_path)
    with pytest.raises(InputError, match="finished"):
        actions.resume_run(tmp_path, "r")
    (d / "run.lock").write_text(json_lock(sleeper.pid, host="another-host.example"))
    with pytest.raises(InputError, match="remote"):
        actions.resume_run(tmp_path, "r")
    # nothing was started: no studio-stderr.txt
    assert not (d / actions.STDERR_NAME).exists()
