"""``population.bin``: every generation's population and fitness, for stepping through a run.

Written by the run loop every ``run.history_every`` generations (0: never); the studio's
arm-ik board and grid-path map step through it. One record per generation, little-endian float64:
``generation, n, d`` then the ``n x d`` genomes (row-major) then the ``n`` fitness values (in
the study's sense; NaN for a failed individual). Records are appended, so the file's byte size
is the resume offset (cut back to the checkpoint like ``stats.csv``). A truncated last record
(a crash mid-write) is ignored by the reader.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from evomotion.errors import FileFormatError
from evomotion.outfile import append_bytes, open_append, truncate_file
from evomotion.textio import read_file_bytes

NAME = "population.bin"
_HEADER = 3
#: a record claiming more values than this is damage, not a population
MAX_VALUES = 1 << 28
MAX_HISTORY_BYTES = 1 << 30  # read_history reads the whole file


class HistoryWriter:
    """Appends one record per generation to ``population.bin``."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        open_append(self.path, "population history", binary=True).close()

    @property
    def offset(self) -> int:
        return self.path.stat().st_size

    def truncate(self, offset: int) -> None:
        truncate_file(self.path, offset, "population history")

    def write(self, generation: int, population: np.ndarray, fitness: np.ndarray) -> None:
        pop = np.asarray(population, dtype="<f8")
        if pop.ndim != 2:
            return
        n, d = pop.shape
        rec = np.concatenate([np.array([generation, n, d], "<f8"), pop.ravel(),
                              np.asarray(fitness, "<f8").ravel()[:n]])
        append_bytes(self.path, rec.tobytes(), "population history")


def read_history(path: Path | str) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """``[(generation, population[n, d], fitness[n]), ...]``; one
    :class:`~evomotion.errors.FileFormatError` line for a damaged file."""
    path = Path(path)
    data = read_file_bytes(path, "population history", MAX_HISTORY_BYTES)
    raw = np.frombuffer(data[:len(data) - len(data) % 8], dtype="<f8")
    out: list[tuple[int, np.ndarray, np.ndarray]] = []
    i = 0
    while i + _HEADER <= raw.size:
        g, n, d = raw[i:i + _HEADER]
        if not (np.isfinite([g, n, d]).all() and n >= 0 and d >= 0 and n == int(n)
                and d == int(d) and d <= MAX_VALUES and n * (d + 1) <= MAX_VALUES):
            raise FileFormatError(path, None, f"record at byte {8 * i}: expected a header "
                                  f"'generation, n, d' of whole numbers, got {g}, {n}, {d}")
        n, d = int(n), int(d)
        end = i + _HEADER + n * d + n
        if end > raw.size:
            break  # a record cut short by a crash
        body = raw[i + _HEADER:end]
        out.append((int(g), body[:n * d].reshape(n, d), body[n * d:]))
        i = end
    return out
