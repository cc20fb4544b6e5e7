"""Fault injection for checking the run loop's promises: a run interrupted (Ctrl-C) or killed
(``kill -9``) during a given step, exactly there, whatever the study (tests, benchmarks)."""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator
from contextlib import contextmanager

from evomotion.run import runner

HOW = {"interrupt": None, "sigint": signal.SIGINT, "sigkill": signal.SIGKILL}


@contextmanager
def fault_at(step: int, how: str = "interrupt") -> Iterator[None]:
    """Within the block, every run's driver fails when step ``step`` (0-based) starts:
    ``interrupt`` raises ``KeyboardInterrupt`` there, ``sigint`` / ``sigkill`` send that signal
    to this process."""
    if how not in HOW:
        raise ValueError(f"unknown fault {how!r}; available: {', '.join(HOW)}")
    build = runner.build_driver

    def faulty(*args, **kwargs):
        driver = build(*args, **kwargs)
        real, count = driver.step, {"n": 0}

        def step_once(*a, **k):
            count["n"] += 1
            if count["n"] == step + 1:
                sig = HOW[how]
                if sig is None:
                    raise KeyboardInterrupt
                os.kill(os.getpid(), sig)
            return real(*a, **k)

        driver.step = step_once  # type: ignore[method-assign]
        return driver

    runner.build_driver = faulty
    try:
        yield
    finally:
        runner.build_driver = build


def in_child(fn) -> int:
    """Run ``fn`` in a forked child process; its exit status (``-9`` when it was killed by
    SIGKILL, its return value otherwise). POSIX only; build nothing that starts threads in
    the parent before calling it."""
    import sys
    import traceback

    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        code = 70
        try:
            code = int(fn() or 0)
        except BaseException:  # noqa: BLE001 - reported, then the child ends
            traceback.print_exc()
        finally:
            os._exit(code)
    _, status = os.waitpid(pid, 0)
    return -os.WTERMSIG(status) if os.WIFSIGNALED(status) else os.WEXITSTATUS(status)


def kill_in_finishing(point: int, count_file=None, after_s: float | None = None) -> None:
    """From the start of a run's finishing phase (its final artifacts), count every write
    event of :mod:`evomotion.outfile` (a file begun, a file's bytes complete before its rename,
    a line appended) and SIGKILL this process at event ``point`` (0: as the phase starts; a
    point past the last event: never). ``count_file`` (a path) receives the running count and
    the seconds since the phase began, as JSON. With ``after_s`` the process is killed that
    many seconds into the phase instead (a point between write events). For a child process:
    it changes this process for good."""
    import json
    import threading
    import time

    from evomotion import outfile

    seen = {"on": False, "n": 0, "t0": 0.0}
    real = runner._finish

    def finish(*a, **kw):
        seen["on"], seen["t0"] = True, time.perf_counter()
        if point == 0 and after_s is None:
            os.kill(os.getpid(), signal.SIGKILL)
        if after_s is not None:
            timer = threading.Timer(after_s, os.kill, (os.getpid(), signal.SIGKILL))
            timer.daemon = True
            timer.start()
        return real(*a, **kw)

    def hook(event, path) -> None:
        if seen["on"]:
            seen["n"] += 1
            if seen["n"] == point and after_s is None:
                os.kill(os.getpid(), signal.SIGKILL)
            if count_file is not None:
                with open(count_file, "w") as fh:
                    json.dump({"events": seen["n"],
                               "seconds": time.perf_counter() - seen["t0"]}, fh)

    runner._finish = finish
    outfile.WRITE_HOOKS.append(hook)
