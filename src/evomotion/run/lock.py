"""An exclusive lock on a run folder for as long as a run or resume writes to it.

``run.lock`` in the run folder is locked with ``flock`` (released by the kernel when the
process ends, however it ends, ``kill -9`` included) and holds the owner's pid and host while it
is held; a clean release empties it. A second process that tries to write to the folder gets a
one-line :class:`~evomotion.errors.InputError` naming the owner. A lock file that still names a
process but is not locked was left by a process that died: it is taken over, and the run log
says so.
"""

from __future__ import annotations

import os
import socket
from pathlib import Path

from evomotion.errors import InputError

LOCK_NAME = "run.lock"


class RunLock:
    """``with RunLock(run_dir) as lock: ...``; ``lock.stale_owner`` names a dead previous owner."""

    def __init__(self, run_dir: Path) -> None:
        self.path = Path(run_dir) / LOCK_NAME
        self.fd: int | None = None
        self.stale_owner: str | None = None

    def acquire(self) -> RunLock:
        import fcntl

        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            owner = _read(fd)
            os.close(fd)
            raise InputError(f"{self.path.parent}: another run is writing to this folder "
                             f"({owner or 'owner unknown'}); wait for it or use another "
                             "--out") from None
        previous = _read(fd)
        if previous:
            self.stale_owner = previous
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"pid {os.getpid()} on {socket.gethostname()}\n".encode(), 0)
        os.fsync(fd)
        self.fd = fd
        return self

    def release(self) -> None:
        if self.fd is None:
            return
        import fcntl

        try:
            os.ftruncate(self.fd, 0)
            fcntl.flock(self.fd, fcntl.LOCK_UN)
        finally:
            os.close(self.fd)
            self.fd = None

    def __enter__(self) -> RunLock:
        return self.acquire()

    def __exit__(self, *exc: object) -> None:
        self.release()


def lock_owner(run_dir: Path) -> tuple[int, str] | None:
    """``(pid, host)`` named in the run folder's ``run.lock`` (written by :class:`RunLock`),
    or ``None`` when it is absent, empty (a clean release) or not in that form. Whether the
    lock is still held is not checked (that would take it)."""
    try:
        parts = (Path(run_dir) / LOCK_NAME).read_text(errors="replace").split()
    except OSError:
        return None
    if len(parts) < 4 or parts[0] != "pid" or not parts[1].isdigit() or parts[2] != "on":
        return None
    return int(parts[1]), parts[3]


def _read(fd: int) -> str:
    try:
        return os.pread(fd, 200, 0).decode("utf-8", "replace").strip()
    except OSError:
        return ""
