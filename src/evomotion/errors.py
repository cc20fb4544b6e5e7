"""User-facing errors: the CLI prints them as one line and exits non-zero (no traceback)."""

from __future__ import annotations

from pathlib import Path


class InputError(ValueError):
    """Bad user input (file, config, CLI argument). ``str()`` is the one-line message."""


class FileFormatError(InputError):
    """A malformed input file; the message names the file, the line and what was expected."""

    def __init__(self, path: str | Path, line: int | None, expected: str) -> None:
        where = f"{path}:{line}" if line is not None else f"{path}"
        super().__init__(f"{where}: {expected}")
        self.path = str(path)
        self.line = line
        self.expected = expected


class ClusterError(RuntimeError):
    """The cluster cannot evaluate any more (lost, or its workers cannot run the problem).

    The runner checkpoints the last completed generation; ``evomotion resume DIR
    --evaluator serial`` (or ``process``) continues from there.
    """
