"""Run folders and atomic file writes."""

from __future__ import annotations

import json
import os
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.errors import InputError

RUN_MARKERS = ("config.toml", "stats.csv", "checkpoints")


def holds_run(path: Path) -> bool:
    """Whether ``path`` already holds (part of) a run folder."""
    return any((path / m).exists() for m in RUN_MARKERS)


def make_run_dir(study: str, out: Path | str | None = None, root: Path | str = "runs") -> Path:
    """``out`` if given (created), else ``runs/<study>-<YYYYmmdd-HHMMSS>[-N]``; every problem
    creating it is one :class:`InputError` line. (Whether the folder already holds a run is
    the run loop's check, under the folder's lock: :func:`evomotion.run.runner.run_study`.)"""
    if out is not None:
        path = Path(out)
    else:
        stamp = time.strftime("%Y%m%d-%H%M%S")
        path = Path(root) / f"{study}-{stamp}"
        n = 1
        while path.exists():
            n += 1
            path = Path(root) / f"{study}-{stamp}-{n}"
    if path.exists() and not path.is_dir():
        raise InputError(f"--out {path}: expected a folder, found a file")
    try:
        path.mkdir(parents=True, exist_ok=True)
        probe = path / f".write-test-{os.getpid()}"
        probe.touch()
        probe.unlink()
    except OSError as e:
        raise InputError(f"--out {path}: cannot create the run folder "
                         f"({e.strerror or type(e).__name__})") from None
    return path


def empty_run_dir(path: Path, keep: tuple[str, ...] = ("run.lock",)) -> None:
    """Remove everything in the run folder ``path`` but ``keep`` (``--overwrite``)."""
    import shutil

    if not holds_run(path):
        raise InputError(f"{path}: not a run folder; --overwrite only empties run folders")
    for child in path.iterdir():
        if child.name in keep:
            continue
        if child.is_dir() and not child.is_symlink():
            shutil.rmtree(child)
        else:
            child.unlink()


def clean_temporaries(run_dir: Path) -> int:
    """Remove the temporary files an interrupted atomic write left behind; their number."""
    n = 0
    for d in (run_dir, run_dir / "checkpoints"):
        if d.is_dir():
            for tmp in d.glob(".*.tmp"):
                tmp.unlink(missing_ok=True)
                n += 1
    return n


def atomic_write_bytes(path: Path | str, data: bytes) -> None:
    """Write ``data`` to ``path`` via a temporary file and ``os.replace`` (crash-safe)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    _fsync_dir(path.parent)


def _fsync_dir(folder: Path) -> None:
    """Make a rename in ``folder`` durable (POSIX; a no-op where folders cannot be opened)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def atomic_write_text(path: Path | str, text: str) -> None:
    atomic_write_bytes(path, text.encode())


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return _clean(obj.tolist())
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, float) and not np.isfinite(obj):
        return None
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def write_json(path: Path | str, obj: Any) -> None:
    """Atomic JSON write; numpy arrays become lists, non-finite floats ``null``."""
    text = json.dumps(_clean(obj), indent=2, default=_jsonable, allow_nan=False)
    atomic_write_text(path, text + "\n")


def _clean(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_clean(v) for v in obj]
    if isinstance(obj, float | np.floating) and not np.isfinite(obj):
        return None
    return obj
