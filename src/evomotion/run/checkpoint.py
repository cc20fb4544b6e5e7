"""Atomic, checked checkpoints as ``npz`` (arrays) + JSON (scalars, RNG state, logger offsets).

A checkpoint is written to ``checkpoints/gen-XXXXXX.{npz,json}``; the JSON is written last and
names its npz, so a crash between the two writes leaves the previous checkpoint as the latest
complete one. ``latest.json`` points at the newest. No pickle is used.

Reading trusts nothing: every field of the JSON is checked against a schema (types, finite
numbers, ranges), the npz name must be a checkpoint of this folder (no path), the offsets must
fit the run's ``stats.csv`` and ``log.txt`` at line boundaries, and the caller's ``accept``
(restoring the driver state and checking it against the run's config) must succeed. A damaged
checkpoint is skipped for the newest valid one before it; :func:`load_checkpoint` says which.
"""

from __future__ import annotations

import io
import json
import math
import os
import re
import stat
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.errors import InputError
from evomotion.npzio import read_npz
from evomotion.outfile import atomic_write_bytes, atomic_write_text
from evomotion.run.history import NAME as HISTORY_NAME
from evomotion.textio import decode_utf8, loads_json, read_file_bytes

NAME = re.compile(r"gen-(\d{6,})\.json")
ARRAYS = re.compile(r"gen-(\d{6,})\.npz")
MAX_META_BYTES = 64 * 1024 * 1024
MAX_META_DEPTH = 16  # a checkpoint's JSON is 4 deep; a driver's state may add a few levels
MAX_ARRAYS_BYTES = 1 << 30  # the largest population arrays a checkpoint holds (1 GiB)


class CheckpointError(ValueError):
    """One checkpoint is unusable (the message says why); older ones may still be."""


def save_checkpoint(run_dir: Path, generation: int, arrays: dict[str, np.ndarray] | None,
                    meta: dict[str, Any], keep: int = 3) -> Path:
    """Write checkpoint ``generation``: its arrays (npz) first, then its JSON, then
    ``latest.json``. ``arrays=None`` rewrites only the JSON of a checkpoint whose arrays are
    written already (the run loop records that its final artifacts are done)."""
    ck = Path(run_dir) / "checkpoints"
    ck.mkdir(parents=True, exist_ok=True)
    stem = f"gen-{generation:06d}"
    if arrays is not None:
        buf = io.BytesIO()
        np.savez(buf, **arrays)  # type: ignore[arg-type]  # numpy's stub: allow_pickle
        atomic_write_bytes(ck / f"{stem}.npz", buf.getvalue())
    meta = dict(meta, arrays_file=f"{stem}.npz", generation=generation)
    atomic_write_text(ck / f"{stem}.json", json.dumps(meta, allow_nan=True))
    atomic_write_text(ck / "latest.json", json.dumps({"checkpoint": f"{stem}.json"}))
    old = sorted(ck.glob("gen-*.json"))[:-keep] if keep > 0 else []
    for j in old:
        j.unlink(missing_ok=True)
        j.with_suffix(".npz").unlink(missing_ok=True)
    return ck / f"{stem}.json"


def candidates(run_dir: Path) -> list[str]:
    """Checkpoint JSON names, the one ``latest.json`` points at first, then newest first."""
    ck = Path(run_dir) / "checkpoints"
    names = sorted((p.name for p in ck.glob("gen-*.json") if NAME.fullmatch(p.name)),
                   key=lambda n: int(n[4:-5]), reverse=True)  # gen-NNNNNN.json
    try:
        path = ck / "latest.json"
        latest = loads_json(decode_utf8(read_file_bytes(path, "checkpoint pointer", 4096), path),
                            path)["checkpoint"]
    except (InputError, KeyError, TypeError):
        latest = None
    if isinstance(latest, str) and latest in names:
        names.remove(latest)
        names.insert(0, latest)
    return names


def load_checkpoint(run_dir: Path, accept: Callable[[dict, dict], Any] | None = None,
                    names: list[str] | None = None
                    ) -> tuple[dict[str, np.ndarray], dict[str, Any], Any, list[str]]:
    """The newest valid checkpoint among ``names`` (default: :func:`candidates`):
    ``(arrays, meta, accepted, notes)``; ``accepted`` is what ``accept(arrays, meta)``
    returned, ``notes`` one line per damaged checkpoint skipped."""
    run_dir = Path(run_dir)
    names = candidates(run_dir) if names is None else names
    if not names:
        raise InputError(f"{run_dir}: no checkpoint to resume from (checkpoints/ is empty)")
    notes = []
    for name in names:
        try:
            arrays, meta = read_checkpoint(run_dir, name)
            accepted = accept(arrays, meta) if accept is not None else None
        except CheckpointError as e:
            notes.append(f"checkpoints/{name}: {e}")
            continue
        return arrays, meta, accepted, notes
    raise InputError(f"{run_dir}: no valid checkpoint to resume from ({'; '.join(notes)})")


def read_checkpoint(run_dir: Path, name: str) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    ck = run_dir / "checkpoints"
    path = ck / name
    try:
        meta = loads_json(decode_utf8(read_file_bytes(path, "checkpoint", MAX_META_BYTES),
                                      path), path, max_depth=MAX_META_DEPTH, finite=False)
    except InputError as e:
        raise CheckpointError(f"unreadable ({str(e).split(': ', 1)[-1][:120]})") from None
    check_meta(meta, run_dir)
    try:
        arrays = read_npz(ck / meta["arrays_file"], "checkpoint arrays", MAX_ARRAYS_BYTES)
    except InputError as e:
        raise CheckpointError(f"{meta['arrays_file']} is unreadable "
                              f"({str(e).split(': ', 1)[-1][:160]})") from None
    return arrays, meta


def check_meta(meta: Any, run_dir: Path) -> None:
    """Raise :class:`CheckpointError` unless ``meta`` has the shape this program writes."""
    if not isinstance(meta, dict):
        raise CheckpointError("expected a JSON object")
    name = meta.get("arrays_file")
    if not isinstance(name, str) or not ARRAYS.fullmatch(name):
        raise CheckpointError(f"arrays_file: expected gen-NNNNNN.npz in checkpoints/, "
                              f"got {name!r}")
    rng = meta.get("rng")
    if not (isinstance(rng, dict) and isinstance(rng.get("bit_generator"), str)
            and rng["bit_generator"] in ("PCG64", "PCG64DXSM", "Philox", "SFC64", "MT19937")
            and isinstance(rng.get("state"), dict)):
        raise CheckpointError("rng: expected a numpy bit generator state")
    c = meta.get("counters")
    if not isinstance(c, dict):
        raise CheckpointError("counters: expected an object")
    _int(c, "generation", -1)
    _int(c, "evaluations", 0)
    _int(c, "failed_total", 0)
    _number(c, "wall_s")
    for k in ("hist_best", "hist_mean"):
        v = c.get(k)
        if not isinstance(v, list) or not all(_is_num(x, allow_inf=True) for x in v):
            raise CheckpointError(f"counters.{k}: expected a list of numbers")
    bm = c.get("best_metrics")
    if not isinstance(bm, dict) or not all(isinstance(k, str) and (
            v is None or _is_num(v, allow_inf=True, allow_nan=True)) for k, v in bm.items()):
        raise CheckpointError("counters.best_metrics: expected names and numbers")
    if c.get("stop_reason") is not None and not isinstance(c["stop_reason"], str):
        raise CheckpointError("counters.stop_reason: expected a string or null")
    if c.get("finished") is not None and not isinstance(c["finished"], bool):
        raise CheckpointError("counters.finished: expected true, false or absent")
    if meta.get("generation") != max(c["generation"], 0):
        raise CheckpointError("generation: does not match counters.generation")
    for key, file in (("stats_offset", "stats.csv"), ("log_offset", "log.txt"),
                      ("history_offset", HISTORY_NAME)):
        if key == "history_offset" and key not in c:
            continue  # a run without history, or written before it was recorded
        off = _int(c, key, 0)
        path = run_dir / file
        try:
            st = os.stat(path)
        except FileNotFoundError:
            st = None
        except OSError as e:
            raise CheckpointError(f"{file}: unreadable ({e.strerror})") from None
        if st is not None and not stat.S_ISREG(st.st_mode):
            raise CheckpointError(f"{file}: expected a regular file")
        size = st.st_size if st is not None else 0
        if off > size:
            raise CheckpointError(f"counters.{key}: {off} is past the end of {file} "
                                  f"({size} bytes: the file was cut or replaced)")
        if off > 0 and key != "history_offset":
            with open(path, "rb") as fh:
                fh.seek(off - 1)
                if fh.read(1) != b"\n":
                    raise CheckpointError(f"counters.{key}: {off} is not a line end of {file}")


def _is_num(v: Any, allow_inf: bool = False, allow_nan: bool = False) -> bool:
    if isinstance(v, bool) or not isinstance(v, int | float):
        return False
    if isinstance(v, float) and math.isnan(v):
        return allow_nan
    return allow_inf or math.isfinite(v)


def _int(c: dict, key: str, low: int) -> int:
    v = c.get(key)
    if isinstance(v, bool) or not isinstance(v, int) or v < low:
        raise CheckpointError(f"counters.{key}: expected an integer >= {low}, got {v!r}")
    return v


def _number(c: dict[str, Any], key: str) -> float:
    v: Any = c.get(key)
    if not _is_num(v) or v < 0:
        raise CheckpointError(f"counters.{key}: expected a finite number >= 0, got {v!r}")
    return float(v)
