"""Per-generation statistics written to ``stats.csv``."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from evomotion.errors import FileFormatError
from evomotion.outfile import append_text, open_append, truncate_file
from evomotion.textio import read_file_bytes

MAX_STATS_BYTES = 64 * 1024 * 1024  # some 300,000 generations
MAX_STATS_CELLS = 1 << 24  # 16 million numbers (128 MB as floats)
COLUMNS = ("generation", "evaluations", "best", "mean", "median", "min", "max", "std",
           "best_so_far", "wall_s", "evals_per_s", "diversity", "failed")


def population_stats(fitness: np.ndarray) -> dict[str, float]:
    """Statistics over the finite fitness values of a population (NaN if none)."""
    f = np.asarray(fitness, dtype=float).ravel()
    if not np.isfinite(f).all():
        f = f[np.isfinite(f)]
    n = f.size
    if n == 0:
        return dict.fromkeys(("mean", "median", "min", "max", "std"), float("nan"))
    # the values of np.mean / np.median / np.std, without their per-call overhead (this
    # runs once per generation of every run, however cheap the generation)
    mean = f.sum() / n
    d = f - mean
    s = np.sort(f)
    k = n // 2
    median = s[k] if n % 2 else (s[k - 1] + s[k]) / 2.0
    return {"mean": float(mean), "median": float(median), "min": float(s[0]),
            "max": float(s[-1]), "std": float(np.sqrt((d * d).sum() / n))}


def diversity(pop: np.ndarray, span: np.ndarray) -> float:
    """Mean per-gene standard deviation, as a fraction of each gene's range."""
    if not len(pop):
        return float("nan")
    s = np.where(span > 0, span, 1.0)
    d = pop - pop.sum(0) / len(pop)
    return float((np.sqrt((d * d).sum(0) / len(pop)) / s).sum() / pop.shape[1])


class StatsWriter:
    """Appends rows to ``stats.csv``; ``offset`` is the byte size used for resume."""

    def __init__(self, path: Path, columns: tuple[str, ...] = COLUMNS) -> None:
        self.path = Path(path)
        self.columns = columns
        open_append(self.path, "stats file").close()
        if self.path.stat().st_size == 0:
            append_text(self.path, ",".join(columns) + "\n", "stats file")

    def truncate(self, offset: int) -> None:
        truncate_file(self.path, offset, "stats file")

    @property
    def offset(self) -> int:
        return self.path.stat().st_size

    def write(self, row: dict[str, float]) -> None:
        buf = io.StringIO()
        csv.writer(buf).writerow([_fmt(row.get(c, "")) for c in self.columns])
        append_text(self.path, buf.getvalue(), "stats file")


class MemoryStats:
    """The same interface as :class:`StatsWriter`, keeping rows in memory (no-folder runs)."""

    def __init__(self, columns: tuple[str, ...] = COLUMNS) -> None:
        self.columns = columns
        self.rows: list[dict] = []

    @property
    def offset(self) -> int:
        return len(self.rows)

    def truncate(self, offset: int) -> None:
        del self.rows[offset:]

    def write(self, row: dict) -> None:
        self.rows.append(dict(row))


def _fmt(v: object) -> str:
    if isinstance(v, float):
        return repr(v)
    return str(v)


def read_stats(path: Path) -> dict[str, np.ndarray]:
    """``stats.csv`` as columns of floats; a cell that is not a number (a study's text column,
    such as arm-ik's ``phase``) reads as NaN. Bounded: at most :data:`MAX_STATS_BYTES` and
    :data:`MAX_STATS_CELLS` cells, held as float arrays (a few bytes a cell, not a dict a row),
    and a damaged file (generation or evaluations decreasing) is one line."""
    data = read_file_bytes(path, "stats file", MAX_STATS_BYTES)
    reader = csv.reader(io.StringIO(data.decode("utf-8", "replace")))
    try:
        header = next(reader, None)
        if not header:
            return {}
        keys = [(i, k) for i, k in enumerate(header) if k]
        chunks: list[np.ndarray] = []
        rows: list[list[float]] = []
        cells = 0
        for row in reader:
            rows.append([_float(row[i]) if i < len(row) else float("nan") for i, _ in keys])
            cells += len(keys)
            if cells > MAX_STATS_CELLS:
                raise FileFormatError(path, None, f"expected at most {MAX_STATS_CELLS} cells")
            if len(rows) == 4096:
                chunks.append(np.array(rows, dtype=float).reshape(-1, len(keys)))
                rows = []
    except csv.Error as e:
        raise FileFormatError(path, None, f"expected CSV ({e})") from None
    if rows:
        chunks.append(np.array(rows, dtype=float).reshape(-1, len(keys)))
    if not chunks:
        return {}
    table = np.concatenate(chunks)
    out: dict[str, np.ndarray] = {}
    for j, (_, k) in enumerate(keys):
        col = table[:, j]
        if k in ("generation", "evaluations") and not np.all(np.diff(col) >= 0):
            raise FileFormatError(path, None, f"column {k}: expected numbers that never "
                                              "decrease (the file is damaged)")
        out.setdefault(k, col)
    return out


def step_values(grid: np.ndarray, x: np.ndarray, y: np.ndarray, hold: bool = True) -> np.ndarray:
    """``y`` of the last row with ``x <= grid`` (a step function, NaN before the first row);
    after the last row its value (``hold``) or NaN."""
    idx = np.searchsorted(x, grid, side="right") - 1
    out = np.where(idx >= 0, y[np.clip(idx, 0, None)], np.nan)
    return out if hold else np.where(grid <= x[-1], out, np.nan)


def _float(v: object) -> float:
    try:
        return float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return float("nan")
