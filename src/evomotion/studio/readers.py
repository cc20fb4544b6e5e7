"""How the studio reads run folders it does not trust: bounded, never blocking, time-limited.

A run folder is whatever sits below RUNS_DIR: a log that is a FIFO, a ``config.toml`` naming
``/dev/zero`` as its robot, a 6 GB ``stats.csv``, a name with a NUL in a URL. Every read here
refuses anything but a regular file without blocking (the file is opened ``O_NONBLOCK`` and
checked with ``fstat``, as :func:`evomotion.textio.read_file_bytes` does) and reads at most a
stated number of bytes; whole small files go through :func:`~evomotion.textio.read_file_bytes`
/ :func:`~evomotion.textio.read_json` themselves. :func:`timed` runs a function on a daemon
worker with a time limit, so that one folder on a slow or hung disk cannot hold up a listing;
a folder still busy from an earlier call is not asked again until it answers.
"""

from __future__ import annotations

import os
import queue
import re
import stat
import threading
from collections.abc import Callable
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeout
from pathlib import Path
from typing import Any

from evomotion.errors import InputError
from evomotion.textio import kind_of

#: the longest name or path a request may carry
MAX_NAME_CHARS = 1024
#: the largest robot spec (TOML) and MJCF file the studio loads for a run's 3D view
MAX_SPEC_BYTES = 1 << 20
MAX_MJCF_BYTES = 64 << 20


def one_line(text: object, limit: int = 300) -> str:
    """``text`` with every control character replaced (no forged lines), at most ``limit``
    characters."""
    s = "".join(c if c.isprintable() else "?" for c in str(text))
    return s if len(s) <= limit else s[:limit - 3] + "..."


def check_name(name: object, what: str = "run") -> str:
    """``name`` (a run name or a path below RUNS_DIR from a request) if it is text a file
    system can take: no NUL or other control character, valid UTF-8, at most
    :data:`MAX_NAME_CHARS`; else one :class:`InputError` line."""
    if not isinstance(name, str):
        raise InputError(f"expected a {what} name, got {type(name).__name__}")
    if len(name) > MAX_NAME_CHARS:
        raise InputError(f"{what} name of {len(name)} characters: expected at most "
                         f"{MAX_NAME_CHARS}")
    try:
        name.encode("utf-8")
    except UnicodeEncodeError:
        raise InputError(f"{one_line(ascii(name), 80)}: expected a {what} name in UTF-8"
                         ) from None
    if any(not c.isprintable() for c in name):
        raise InputError(f"{one_line(name, 80)}: a {what} name cannot hold control "
                         "characters (NUL, newline, ...)")
    return name


def regular_size(path: Path, what: str, max_bytes: int) -> int:
    """The size of the regular file ``path`` (links followed), or one :class:`InputError`:
    missing, not a regular file (a FIFO, a device, ...), or larger than ``max_bytes``."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise InputError(f"{one_line(path)}: no such {what}") from None
    except (OSError, ValueError) as e:
        raise InputError(f"{one_line(path)}: cannot read the {what} ({_why(e)})") from None
    k = kind_of(st.st_mode)
    if k is not None:
        raise InputError(f"{one_line(path)}: expected a regular file for the {what}, found {k}")
    if st.st_size > max_bytes:
        raise InputError(f"{one_line(path)}: the {what} has {st.st_size} bytes; the studio "
                         f"reads at most {max_bytes}")
    return st.st_size


def _why(e: BaseException) -> str:
    return one_line(getattr(e, "strerror", None) or e or type(e).__name__, 120)


def read_range(path: Path, start: int, n: int) -> tuple[bytes, int]:
    """Up to ``n`` bytes of the regular file ``path`` from byte ``start`` (a negative
    ``start`` counts from the end) and the file's size; ``(b"", 0)`` for a missing file or
    anything but a regular file (never opened in a way that blocks)."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0))
    except (OSError, ValueError):
        return b"", 0
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            return b"", 0
        size = st.st_size
        begin = max(0, size + start) if start < 0 else min(start, size)
        return os.pread(fd, max(0, min(n, size - begin)), begin), size
    except OSError:
        return b"", 0
    finally:
        os.close(fd)


_NUMBER = re.compile(r"([+-]?\d+(?:\.\d+)?)")


def natural_key(name: str) -> tuple:
    """Sort key reading signed numbers in ``name`` by value (text parts as text)."""
    parts = _NUMBER.split(name)
    return tuple((0, float(p), "") if i % 2 else (1, 0.0, p) for i, p in enumerate(parts))


def head_tail(path: Path, n: int = 16384, head: int = 4096) -> tuple[str, str]:
    """The first line (at most ``head`` bytes) and the last ``n`` bytes of a text file
    ('' where it is missing or not a regular file)."""
    first, _ = read_range(path, 0, head)
    tail, _ = read_range(path, -n, n) if n > 0 else (b"", 0)
    return (first.split(b"\n", 1)[0].decode("utf-8", "replace").strip(),
            tail.decode("utf-8", "replace"))


def check_robot(robot: object) -> str:
    """``robot`` (a run config's ``problem.robot``) if the studio may load it: a bundled
    robot name, or a spec file that is a regular file of at most :data:`MAX_SPEC_BYTES`
    whose MJCF is a regular file of at most :data:`MAX_MJCF_BYTES`; else one
    :class:`InputError` line (nothing is loaded)."""
    from evomotion.sim.robots import bundled_robots

    names = bundled_robots()
    head = f"problem.robot = {one_line(repr(robot), 120)}"
    if not isinstance(robot, str):
        raise InputError(f"{head}: expected a robot name or a spec path")
    if robot in ("", *names):
        return robot
    expected = f"expected a bundled robot ({', '.join(names)}) or a robot spec file"
    try:
        check_name(robot, "robot")
        regular_size(Path(robot), "robot spec", MAX_SPEC_BYTES)
    except InputError as e:
        raise InputError(f"{head}: {expected}; {e}") from None
    from evomotion.sim.robots.build import resolve_mjcf
    from evomotion.sim.robots.spec import read_spec

    try:
        mjcf = resolve_mjcf(read_spec(robot))
        regular_size(mjcf, "MJCF file", MAX_MJCF_BYTES)
    except (ValueError, OSError) as e:  # InputError is a ValueError
        raise InputError(f"{head}: {one_line(e)}") from None
    return robot


def bounded_files(folder: Path, suffix: str, max_depth: int = 3, max_entries: int = 5000,
                  skip: tuple[str, ...] = ("checkpoints",)) -> list[Path]:
    """The regular files named ``*suffix`` below ``folder`` (links not followed, at most
    ``max_depth`` folders down and ``max_entries`` entries looked at)."""
    out: list[Path] = []
    seen = 0
    todo = [(Path(folder), 0)]
    while todo and seen < max_entries:
        d, depth = todo.pop()
        try:
            with os.scandir(d) as it:
                for e in it:
                    seen += 1
                    if seen > max_entries:
                        break
                    if e.is_dir(follow_symlinks=False):
                        if depth < max_depth and e.name not in skip:
                            todo.append((Path(e.path), depth + 1))
                    elif e.name.endswith(suffix) and e.is_file(follow_symlinks=False):
                        out.append(Path(e.path))
        except OSError:
            continue
    return out


class _Workers:
    """Daemon threads running submitted calls (a call stuck on a hung disk never keeps the
    studio from exiting, unlike a ``ThreadPoolExecutor``'s threads)."""

    def __init__(self, n: int) -> None:
        self.n = n
        self.jobs: queue.SimpleQueue = queue.SimpleQueue()
        self.threads: list[threading.Thread] = []
        self.lock = threading.Lock()

    def submit(self, fn: Callable[..., Any], *args: Any) -> Future:
        fut: Future = Future()
        self.jobs.put((fut, fn, args))
        with self.lock:
            if len(self.threads) < self.n:
                t = threading.Thread(target=self._loop, name="studio-reader", daemon=True)
                t.start()
                self.threads.append(t)
        return fut

    def _loop(self) -> None:
        while True:
            fut, fn, args = self.jobs.get()
            if not fut.set_running_or_notify_cancel():
                continue
            try:
                fut.set_result(fn(*args))
            except BaseException as e:  # noqa: BLE001 - handed to the caller
                fut.set_exception(e)


_WORKERS = _Workers(16)
_BUSY: dict[Any, Future] = {}
_BUSY_LOCK = threading.Lock()


def timed(calls: list[tuple[Any, Callable[..., Any], tuple]], timeout_s: float
          ) -> dict[Any, tuple[str, Any]]:
    """Run ``fn(*args)`` for every ``(key, fn, args)`` on the worker threads and wait at most
    ``timeout_s`` in all: ``{key: ("ok", result) | ("error", exception) | ("timeout",
    None)}``. A key whose call from an earlier time has not returned yet is not called again
    (``"timeout"`` at once), so a hung folder ties up one worker, not one per refresh."""
    futures: dict[Any, Future | None] = {}
    with _BUSY_LOCK:
        for key, fn, args in calls:
            old = _BUSY.get(key)
            if old is not None and not old.done():
                futures[key] = None
                continue
            futures[key] = _BUSY[key] = _WORKERS.submit(fn, *args)
    out: dict[Any, tuple[str, Any]] = {}
    deadline = _now() + timeout_s
    for key, fut in futures.items():
        if fut is None:
            out[key] = ("timeout", None)
            continue
        try:
            out[key] = ("ok", fut.result(timeout=max(0.0, deadline - _now())))
        except FutureTimeout:
            out[key] = ("timeout", None)
        except Exception as e:  # noqa: BLE001 - reported per folder by the caller
            out[key] = ("error", e)
    with _BUSY_LOCK:
        for key, fut in futures.items():
            if fut is not None and fut.done() and _BUSY.get(key) is fut:
                del _BUSY[key]
    return out


def _now() -> float:
    import time

    return time.monotonic()
