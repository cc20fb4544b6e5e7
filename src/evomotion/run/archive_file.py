"""``archive.npz``: the elites of a quality-diversity run, for users, plots and studies.

Written (atomically) by the run loop at every checkpoint and at the end of a run whose
optimizer keeps an archive. Plain arrays, no pickle: per filled cell its index, centre,
elite genome, objective (maximised) and measures, plus the archive's kind, bins, ranges and
measure names. :func:`read_archive` checks every field and raises a one-line
:class:`~evomotion.errors.InputError` naming the file and what was expected.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from evomotion.errors import InputError
from evomotion.npzio import read_npz
from evomotion.outfile import atomic_write_bytes

#: the largest archive.npz read (a million cells of a 100-gene genome is 0.8 GB: refused)
MAX_ARCHIVE_BYTES = 512 * 1024 * 1024
MAX_MEASURES = 16

NAME = "archive.npz"


@dataclass(frozen=True)
class ArchiveFile:
    """The filled cells of an archive (``n`` elites, ``m`` measures, ``d`` genes)."""

    kind: str  # grid | cvt
    bins: np.ndarray  # int[m] for a grid, [] for a CVT
    cells: int
    lower: np.ndarray  # [m]
    upper: np.ndarray
    measure_names: tuple[str, ...]
    cell: np.ndarray  # int[n]
    centre: np.ndarray  # [n, m] the cell's centre (grid) or centroid (CVT)
    solution: np.ndarray  # [n, d]
    objective: np.ndarray  # [n]
    measures: np.ndarray  # [n, m]
    all_centres: np.ndarray  # [cells, m]


def write_archive(path: Path, spec, state, names: tuple[str, ...]) -> None:
    """Write the filled cells of ``state`` (an :class:`~evomotion.core.archives.ArchiveState`
    of ``spec``) to ``path``."""
    occ = np.flatnonzero(state.occupied)
    centres = spec.cell_centres(state)
    buf = io.BytesIO()
    np.savez_compressed(
        buf, kind=np.array(spec.kind), bins=np.asarray(spec.bins, dtype=np.int64),
        cells=np.array(spec.cells), lower=np.asarray(spec.lower, float),
        upper=np.asarray(spec.upper, float), measure_names=np.array(list(names), dtype=str),
        cell=occ.astype(np.int64), centre=centres[occ], solution=state.solutions[occ],
        objective=state.objective[occ], measures=state.measures[occ], all_centres=centres)
    atomic_write_bytes(path, buf.getvalue())


def read_archive(path: Path | str) -> ArchiveFile:
    """Read and check an ``archive.npz`` (one-line errors)."""
    path = Path(path)
    if not path.exists() and not path.is_symlink():
        raise InputError(f"{path}: no such file (a quality-diversity run writes archive.npz)")
    data = read_npz(path, "archive.npz", MAX_ARCHIVE_BYTES)
    need = ("kind", "bins", "cells", "lower", "upper", "measure_names", "cell", "centre",
            "solution", "objective", "measures", "all_centres")
    missing = [k for k in need if k not in data]
    if missing:
        raise InputError(f"{path}: missing field {missing[0]!r} (expected {', '.join(need)})")
    try:
        kind = str(data["kind"].item())
        cells = int(data["cells"].item())
        lower, upper = data["lower"].astype(float), data["upper"].astype(float)
        m = lower.size
        n = int(data["cell"].size)
        ok = (kind in ("grid", "cvt") and cells >= 1 and upper.shape == (m,)
              and data["measure_names"].shape == (m,) and data["centre"].shape == (n, m)
              and data["measures"].shape == (n, m) and data["objective"].shape == (n,)
              and data["solution"].ndim == 2 and data["solution"].shape[0] == n
              and data["all_centres"].shape == (cells, m)
              and data["bins"].ndim == 1 and data["bins"].size <= MAX_MEASURES
              and (kind == "cvt" or math.prod(int(b) for b in data["bins"]) == cells))
        ok = ok and all(np.issubdtype(data[k].dtype, np.integer) for k in ("cell", "bins"))
        cell = data["cell"].astype(np.int64) if ok else np.zeros(0, np.int64)
        ok = ok and bool(np.all((cell >= 0) & (cell < cells))) and \
            np.unique(cell).size == cell.size
        ok = ok and all(bool(np.isfinite(data[k].astype(float)).all()) for k in (
            "lower", "upper", "centre", "objective", "measures", "all_centres", "solution"))
        ok = ok and bool(np.all(lower < upper))
    except (ValueError, TypeError, OverflowError):
        ok = False
    if not ok:
        raise InputError(f"{path}: inconsistent archive arrays (expected n distinct filled "
                         "cells with matching centre, solution, objective and measures rows "
                         "of finite numbers, and lower < upper)")
    return ArchiveFile(kind, data["bins"].astype(np.int64), cells, lower, upper,
                       tuple(str(s) for s in data["measure_names"]), cell,
                       data["centre"].astype(float), data["solution"].astype(float),
                       data["objective"].astype(float), data["measures"].astype(float),
                       data["all_centres"].astype(float))
