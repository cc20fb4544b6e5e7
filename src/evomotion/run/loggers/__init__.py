"""Extra loggers beside ``stats.csv``: ``run.loggers = ["tensorboard", "rerun"]``.

Each logger is an optional extra whose package is imported only when a run names it (a missing
one is a one-line :class:`~evomotion.errors.InputError` before the run starts). The run loop
talks to the run's loggers through :class:`Loggers`:

- ``row(row)`` after every ``stats.csv`` row, with the same dict;
- ``close()`` when the loop ends, however it ends (Ctrl-C, a crash);
- ``finish(ctx)`` at the end of the run, after the study's artifacts (``best.motion``) exist.

A logger class is built as ``Logger(out_dir, replay)``: ``replay`` is the study's hook that
plays its best motion on its own robot (:class:`~evomotion.run.contracts.Replay`, ``None``
when the study has none); a logger never simulates anything itself.

A logger writes only inside the run folder and never changes the results, so ``run.loggers``
may change on resume. Runs without a folder have no loggers.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any, Protocol

from evomotion.core.registry import lookup
from evomotion.errors import InputError
from evomotion.run.context import RunContext
from evomotion.run.contracts import ReplayHook

#: name -> (module with a ``Logger`` class, the module it imports, its pip package, the extra)
LOGGERS: dict[str, tuple[str, str, str, str]] = {
    "tensorboard": ("evomotion.run.loggers.tensorboard", "tensorboardX", "tensorboardX",
                    "tensorboard"),
    "rerun": ("evomotion.run.loggers.rerun", "rerun", "rerun-sdk", "rerun"),
}


def check_names(names: Iterable[str]) -> None:
    """Raise for an unknown logger name ("unknown logger 'x'; available: ...") or a repeat."""
    seen: set[str] = set()
    for name in names:
        lookup(LOGGERS, "logger", name)
        if name in seen:
            raise InputError(f"run.loggers: {name!r} is named twice")
        seen.add(name)


class Logger(Protocol):
    """One logger of ``run.loggers`` (see the module doc)."""

    def row(self, row: dict[str, Any]) -> None: ...

    def close(self) -> None: ...

    def finish(self, ctx: RunContext) -> None: ...


#: a logger class: ``Logger(out_dir, replay)``
LoggerClass = Callable[[Path, ReplayHook | None], Logger]


def _load(name: str) -> LoggerClass:
    module, import_name, package, extra = lookup(LOGGERS, "logger", name)
    try:
        cls: LoggerClass = importlib.import_module(module).Logger
        return cls
    except ImportError as e:
        if (e.name or "").split(".")[0] == import_name:
            raise InputError(f"run.loggers: {name!r} needs the {package} package: "
                             f"pip install 'evomotion[{extra}]'") from None
        raise InputError(f"run.loggers: {name!r}: cannot import {package} "
                         f"({type(e).__name__}: {e})") from None


class Loggers:
    """The run's loggers as one; a logger's failure at the end is a warning in the run log
    (it must not lose the run)."""

    def __init__(self, items: list[tuple[str, Logger]]) -> None:
        self.items = items
        self.notes: list[str] = []

    def row(self, row: dict[str, Any]) -> None:
        for _, logger in self.items:
            logger.row(row)

    def close(self) -> None:
        for name, logger in self.items:
            try:
                logger.close()
            except Exception as e:  # noqa: BLE001 - in a finally: must not hide the real error
                self.notes.append(f"warning: logger {name!r} failed to close: "
                                  f"{type(e).__name__}: {e}")

    def finish(self, ctx: RunContext) -> None:
        """``finish(ctx)`` of each logger, unless the run was interrupted (it ends at once;
        the resumed run finishes them)."""
        for line in self.notes:
            ctx.log(line)
        self.notes.clear()
        if ctx.stop_reason == "interrupted":
            return
        for name, logger in self.items:
            try:
                logger.finish(ctx)
            except Exception as e:  # noqa: BLE001 - an artifact failure must not lose the run
                ctx.log(f"warning: logger {name!r} failed: {type(e).__name__}: {e}")


def check_loggers(names: Iterable[str]) -> None:
    """Refuse (one line) a logger that is unknown or whose package is missing, before a run
    makes or empties its folder (``--overwrite`` must not remove the old run and then refuse)."""
    names = tuple(names)
    check_names(names)
    for name in names:
        _load(name)


def make_loggers(names: Iterable[str], out_dir: Path,
                 replay: ReplayHook | None = None) -> Loggers:
    """The loggers ``names`` for the run folder ``out_dir`` (their packages imported now);
    ``replay``: the study's replay of its best motion (see the module doc)."""
    names = tuple(names)
    check_names(names)
    classes = [(name, _load(name)) for name in names]  # every import error before any file
    return Loggers([(name, cls(Path(out_dir), replay)) for name, cls in classes])
