"""``log.txt`` of a run folder and the SIGTERM-as-Ctrl-C guard of the run loop."""

from __future__ import annotations

import re
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from evomotion.outfile import append_text, open_append
from evomotion.run.console import Reporter


class RunLog:
    """``log.txt`` in the run folder (or nothing, for a run without a folder), mirrored to the
    console reporter."""

    def __init__(self, path: Path | None, reporter: Reporter | None = None) -> None:
        self.path = path
        if self.path is not None:
            open_append(self.path, "run log").close()
        self.reporter = reporter
        self.lines: list[str] = []

    @property
    def offset(self) -> int:
        return self.path.stat().st_size if self.path is not None else len(self.lines)

    def lines_after(self, offset: int) -> int:
        """How many lines the log holds after ``offset`` (a checkpoint's): a resume keeps them
        (the log is the run's history: the stopped session's last generations and its
        ``stopped:`` line), ending a line a kill cut short so the next starts on its own."""
        if self.path is None:
            return max(len(self.lines) - offset, 0)
        with open(self.path, "rb") as f:
            f.seek(offset)
            tail = f.read()
        if tail and not tail.endswith(b"\n"):
            append_text(self.path, "\n", "run log")
            return tail.count(b"\n") + 1
        return tail.count(b"\n")

    def __call__(self, msg: str) -> None:
        msg = one_line(msg)
        if self.path is None:
            self.lines.append(msg)
        else:
            append_text(self.path, msg + "\n", "run log")
        if self.reporter is not None:
            self.reporter.line(msg)


_CONTROL = re.compile(r"[\x00-\x08\x0a-\x1f\x7f\u2028\u2029\x85]")


def one_line(msg: str) -> str:
    """``msg`` as one log line: a newline, carriage return or other control character in it
    (from a file name, a robot name, an error) is shown escaped, so no text can forge a line
    that the studio or a reader takes for the run's own."""
    msg = str(msg).rstrip("\n")
    return _CONTROL.sub(lambda m: m.group().encode("unicode_escape").decode("ascii"), msg)


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
