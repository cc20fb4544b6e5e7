"""An exclusive lock on a run folder for as long as a run or resume writes to it, and the only
way to signal the process that holds it.

``run.lock`` in the run folder is locked with ``flock`` (released by the kernel when the
process ends, however it ends, ``kill -9`` included) and, while it is held, names its owner in
one JSON line: pid, the process's start time (clock ticks since boot, from ``/proc``), the boot
it started in, the host and the command. A clean release empties it. A second process that tries
to write to the folder gets a one-line :class:`~evomotion.errors.InputError` naming the owner. A
lock file that still names an owner but is not locked was left by a process that died: it is
taken over, and the run log says so.

A pid alone names nobody: once the run is gone, the number is reused. :func:`owner_state` says
whether the named process is *that* run (same host, same boot, same start time, an
``evomotion`` command line) and :func:`signal_owner` signals it only then, never pid 0 or 1,
never on another host (through a pidfd where the system has them, so the check and the signal
concern the same process).
"""

from __future__ import annotations

import dataclasses
import errno
import json
import os
import socket
from pathlib import Path
from typing import cast

from evomotion.errors import InputError

LOCK_NAME = "run.lock"
MAX_PID = 1 << 22  # Linux's largest pid_max
_MAX_LOCK_BYTES = 4096


@dataclasses.dataclass(frozen=True)
class LockOwner:
    """Who ``run.lock`` names (``start``/``boot`` are ``None`` in a lock written before they
    were recorded)."""

    pid: int
    host: str
    start: int | None = None
    boot: str | None = None
    command: str = ""

    def describe(self) -> str:
        return f"pid {self.pid} on {self.host}"


class RunLock:
    """``with RunLock(run_dir) as lock: ...``; ``lock.stale_owner`` names a dead previous owner."""

    def __init__(self, run_dir: Path) -> None:
        self.path = Path(run_dir) / LOCK_NAME
        self.fd: int | None = None
        self.stale_owner: str | None = None

    def acquire(self) -> RunLock:
        import fcntl

        from evomotion.outfile import WriteError, kind_of, reason

        try:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_NONBLOCK | os.O_NOFOLLOW,
                         0o644)
        except OSError as e:
            if e.errno == errno.ELOOP:  # a link: it would write (and empty) its target
                raise WriteError(f"{self.path}: expected a regular lock file, found a link"
                                 ) from None
            raise WriteError(f"{self.path}: cannot lock the run folder ({reason(e)})") from None
        kind = kind_of(os.fstat(fd).st_mode)
        if kind is not None:
            os.close(fd)
            raise WriteError(f"{self.path}: expected a regular lock file, found {kind}")
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            owner = parse_owner(_read(fd))
            os.close(fd)
            raise InputError(f"{self.path.parent}: another run is writing to this folder "
                             f"({owner.describe() if owner else 'owner unknown'}); wait for it "
                             "or use another --out") from None
        previous = parse_owner(_read(fd))
        if previous:
            self.stale_owner = previous.describe()
        try:
            os.ftruncate(fd, 0)
            os.pwrite(fd, (json.dumps(dataclasses.asdict(this_process())) + "\n").encode(), 0)
            os.fsync(fd)
        except OSError as e:
            os.close(fd)
            raise WriteError(f"{self.path}: cannot write the lock ({reason(e)})") from None
        self.fd = fd
        return self

    def release(self) -> None:
        if self.fd is None:
            return
        import fcntl

        try:
            os.ftruncate(self.fd, 0)
        except OSError:
            pass  # a full or read-only disk: the kernel still drops the lock below
        finally:
            fcntl.flock(self.fd, fcntl.LOCK_UN)
            os.close(self.fd)
            self.fd = None

    def __enter__(self) -> RunLock:
        return self.acquire()

    def __exit__(self, *exc: object) -> None:
        self.release()


def this_process() -> LockOwner:
    pid = os.getpid()
    return LockOwner(pid, socket.gethostname(), process_start(pid), boot_id(), "evomotion")


def process_start(pid: int) -> int | None:
    """The start time of process ``pid`` in clock ticks since boot (``/proc/PID/stat``
    field 22), or ``None`` when there is no such process or no ``/proc``."""
    try:
        with open(f"/proc/{int(pid)}/stat", "rb") as fh:
            text = fh.read(4096).decode("ascii", "replace")
        return int(text.rsplit(")", 1)[1].split()[19])
    except (OSError, ValueError, IndexError):
        return None


def boot_id() -> str | None:
    try:
        with open("/proc/sys/kernel/random/boot_id", "rb") as fh:
            return fh.read(64).decode("ascii", "replace").strip() or None
    except OSError:
        return None


def _command_line(pid: int) -> str:
    try:
        with open(f"/proc/{int(pid)}/cmdline", "rb") as fh:
            return fh.read(8192).replace(b"\0", b" ").decode("utf-8", "replace")
    except OSError:
        return ""


def parse_owner(text: str) -> LockOwner | None:
    """The owner named by a lock file's text (this format, or the older ``pid N on HOST``),
    or ``None`` when it names none or nothing sensible (a pid outside 1..2^22, say)."""
    text = text.strip()
    if not text:
        return None
    if text.startswith("{"):
        try:
            d = json.loads(text)
        except (ValueError, RecursionError):
            return None
        if not isinstance(d, dict):
            return None
        pid, host, start, boot = d.get("pid"), d.get("host"), d.get("start"), d.get("boot")
        cmd = d.get("command", "")
        ok = (_valid_pid(pid) and _valid_host(host)
              and (start is None or (isinstance(start, int) and not isinstance(start, bool)
                                     and 0 <= start < 1 << 63))
              and (boot is None or (isinstance(boot, str) and len(boot) <= 64))
              and isinstance(cmd, str))
        return LockOwner(cast(int, pid), cast(str, host), start, boot, cmd[:64]) if ok else None
    parts = text.split()
    if len(parts) < 4 or parts[0] != "pid" or parts[2] != "on" or not parts[1].isascii() \
            or not parts[1].isdigit() \
            or len(parts[1]) > 8 or not _valid_pid(int(parts[1])) or not _valid_host(parts[3]):
        return None
    return LockOwner(int(parts[1]), parts[3])


def _valid_pid(pid: object) -> bool:
    return isinstance(pid, int) and not isinstance(pid, bool) and 1 < pid <= MAX_PID


def _valid_host(host: object) -> bool:
    """A host name as ``gethostname`` gives it: 1 to 255 printable characters, no spaces."""
    return isinstance(host, str) and 0 < len(host) <= 255 and host.isprintable() \
        and not any(c.isspace() for c in host)


def lock_owner(run_dir: Path) -> LockOwner | None:
    """The owner named in the run folder's ``run.lock`` (written by :class:`RunLock`), or
    ``None`` when it is absent, empty (a clean release), not a regular file or not in that
    form. Whether the lock is still held is not checked (that would take it)."""
    from evomotion.textio import read_file_bytes

    try:
        data = read_file_bytes(Path(run_dir) / LOCK_NAME, "lock file", _MAX_LOCK_BYTES)
    except InputError:
        return None
    return parse_owner(data.decode("utf-8", "replace"))


def holds_flock(pid: int, path: Path) -> bool:
    """Whether process ``pid`` holds an exclusive ``flock`` on ``path`` (``/proc/locks``)."""
    try:
        st = os.stat(path)
        with open("/proc/locks", "rb") as fh:
            text = fh.read(1 << 20).decode("ascii", "replace")
    except OSError:
        return False
    dev = f"{os.major(st.st_dev):02x}:{os.minor(st.st_dev):02x}:{st.st_ino}"
    for line in text.splitlines():
        f = line.split()
        if "->" in f:  # a waiting lock
            continue
        if len(f) >= 6 and f[1] == "FLOCK" and f[3] == "WRITE" and f[4] == str(pid) \
                and f[5] == dev:
            return True
    return False


def owner_state(owner: LockOwner | None, lock_path: Path | None = None) -> str:
    """``"none"`` (no owner), ``"running"`` (the named process is that run, alive: the same
    start time and boot, and an ``evomotion`` command line or, for a run started from Python,
    the lock ``lock_path`` held by that process),
    ``"stale"`` (it is gone, or the pid now belongs to another process), ``"remote"``
    (it ran on another host: cannot be checked from here) or ``"unknown"`` (this system
    cannot tell: no ``/proc``, or a lock written before start times were recorded whose pid
    is alive)."""
    if owner is None:
        return "none"
    if owner.host != socket.gethostname():
        return "remote"
    start = process_start(owner.pid)
    if start is None:
        if os.path.isdir("/proc"):
            return "stale"
        return "unknown"
    if owner.start is None:  # an older lock: the pid is alive, is it still evomotion?
        return "unknown" if "evomotion" in _command_line(owner.pid) else "stale"
    if start != owner.start or (owner.boot and boot_id() and owner.boot != boot_id()):
        return "stale"
    if "evomotion" in _command_line(owner.pid):
        return "running"
    held = lock_path is not None and holds_flock(owner.pid, lock_path)
    return "running" if held else "stale"  # a run from Python holds the lock itself


def signal_owner(run_dir: Path, sig: int) -> int:
    """Send ``sig`` to the process that holds ``run_dir``'s lock, if it is verifiably that
    run (see :func:`owner_state`); its pid. Anything else is one :class:`InputError` and no
    signal is sent."""
    owner = lock_owner(run_dir)
    lock_path = Path(run_dir) / LOCK_NAME
    state = owner_state(owner, lock_path)
    if owner is None or state == "none":
        raise InputError(f"{run_dir}: the run is not running (no process holds its lock)")
    if state == "remote":
        raise InputError(f"{run_dir}: the run's lock names {owner.describe()}, another host; "
                         "stop it there")
    if state != "running":
        what = "not verifiably this run" if state == "unknown" else \
            "gone or now another process"
        raise InputError(f"{run_dir}: the run's lock names {owner.describe()}, which is {what} "
                         "(a stale lock); no signal sent")
    import signal

    try:
        fd = os.pidfd_open(owner.pid)
    except (AttributeError, OSError):
        fd = None
    try:
        if owner_state(owner, lock_path) != "running":  # again, with the process pinned
            raise InputError(f"{run_dir}: the run's process {owner.pid} ended; no signal sent")
        if fd is not None:
            signal.pidfd_send_signal(fd, sig)
        else:
            os.kill(owner.pid, sig)
    except ProcessLookupError:
        raise InputError(f"{run_dir}: the run's process {owner.pid} ended; no signal "
                         "sent") from None
    except PermissionError:
        raise InputError(f"{run_dir}: not allowed to signal process {owner.pid}") from None
    finally:
        if fd is not None:
            os.close(fd)
    return owner.pid


def _read(fd: int) -> str:
    try:
        return os.pread(fd, _MAX_LOCK_BYTES, 0).decode("utf-8", "replace").strip()
    except OSError:
        return ""
