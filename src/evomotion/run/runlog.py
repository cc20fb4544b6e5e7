"""``log.txt`` of a run folder and the SIGTERM-as-Ctrl-C guard of the run loop."""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from evomotion.run.console import Reporter


class RunLog:
    """``log.txt`` in the run folder (or nothing, for a run without a folder), mirrored to the
    console reporter."""

    def __init__(self, path: Path | None, reporter: Reporter | None = None) -> None:
        self.path = path
        if self.path is not None:
            self.path.touch()
        self.reporter = reporter
        self.lines: list[str] = []

    @property
    def offset(self) -> int:
        return self.path.stat().st_size if self.path is not None else len(self.lines)

    def truncate(self, offset: int) -> None:
        if self.path is None:
            del self.lines[offset:]
            return
        with open(self.path, "r+b") as fh:
            fh.truncate(offset)

    def __call__(self, msg: str) -> None:
        if self.path is None:
            self.lines.append(msg)
        else:
            with open(self.path, "a", encoding="utf-8") as fh:
                fh.write(msg.rstrip("\n") + "\n")
        if self.reporter is not None:
            self.reporter.line(msg)


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Within the block, SIGTERM raises ``KeyboardInterrupt`` (main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        raise KeyboardInterrupt

    old = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)
