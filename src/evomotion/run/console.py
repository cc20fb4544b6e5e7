"""Console reporting: a Rich progress bar on a terminal, throttled plain lines otherwise.

Everything goes to stderr so that ``--json`` style commands keep stdout clean; ``quiet``
silences it all. Plain mode prints at most one line every ``plain_every_s`` seconds plus the
final line.
"""

from __future__ import annotations

import sys
import time

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn


class Reporter:
    def __init__(self, total: int, quiet: bool = False, plain_every_s: float = 10.0,
                 label: str = "run") -> None:
        self.quiet = quiet
        self.console = Console(stderr=True)
        self.fancy = not quiet and self.console.is_terminal
        self.plain_every_s = plain_every_s
        self._last = 0.0
        self._line_last = 0.0
        self.label = label
        self._progress: Progress | None = None
        if self.fancy:
            self._progress = Progress(
                TextColumn("[bold]{task.description}"), BarColumn(),
                TextColumn("gen {task.completed}/{task.total}"),
                TextColumn("best {task.fields[best]} mean {task.fields[mean]}"),
                TimeElapsedColumn(), TimeRemainingColumn(), console=self.console,
                transient=False)
            self._task = self._progress.add_task(label, total=total or None, best="-", mean="-")
            self._progress.start()

    def update(self, generation: int, best: float, mean: float, evals: int) -> None:
        if self.quiet:
            return
        now = time.monotonic()
        if self._progress is not None:
            self._progress.update(self._task, completed=generation, best=f"{best:.6g}",
                                  mean=f"{mean:.6g}")
            if now - self._line_last >= 2.0:  # throttled log line above the bar
                self._line_last = now
                self._progress.console.print(
                    f"gen {generation:5d}  evals {evals:8d}  best {best:.6g}  mean {mean:.6g}",
                    highlight=False)
        elif now - self._last >= self.plain_every_s:
            self._last = now
            self.line(f"{self.label}: gen {generation} evals {evals} best {best:.6g} "
                      f"mean {mean:.6g}")

    def line(self, text: str) -> None:
        if self.quiet:
            return
        if self._progress is not None:
            self._progress.console.print(text, highlight=False)
        else:
            print(text, file=sys.stderr, flush=True)

    def close(self) -> None:
        if self._progress is not None:
            self._progress.stop()
            self._progress = None
