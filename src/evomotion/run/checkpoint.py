"""Atomic checkpoints as ``npz`` (arrays) + JSON (scalars, RNG state, logger offsets).

A checkpoint is written to ``checkpoints/gen-XXXXXX.{npz,json}``; the JSON is written last
and names its npz, so a crash between the two writes leaves the previous checkpoint as the
latest complete one. ``latest.json`` points at the newest. No pickle is used.
"""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.errors import InputError
from evomotion.run.folder import atomic_write_bytes, atomic_write_text


def save_checkpoint(run_dir: Path, generation: int, arrays: dict[str, np.ndarray],
                    meta: dict[str, Any], keep: int = 3) -> Path:
    ck = Path(run_dir) / "checkpoints"
    ck.mkdir(parents=True, exist_ok=True)
    stem = f"gen-{generation:06d}"
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    atomic_write_bytes(ck / f"{stem}.npz", buf.getvalue())
    meta = dict(meta, arrays_file=f"{stem}.npz", generation=generation)
    atomic_write_text(ck / f"{stem}.json", json.dumps(meta))
    atomic_write_text(ck / "latest.json", json.dumps({"checkpoint": f"{stem}.json"}))
    old = sorted(ck.glob("gen-*.json"))[:-keep] if keep > 0 else []
    for j in old:
        j.unlink(missing_ok=True)
        j.with_suffix(".npz").unlink(missing_ok=True)
    return ck / f"{stem}.json"


def load_checkpoint(run_dir: Path) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    ck = Path(run_dir) / "checkpoints"
    latest = ck / "latest.json"
    if not latest.exists():
        raise InputError(f"{run_dir}: no checkpoint to resume from (checkpoints/latest.json)")
    name = json.loads(latest.read_text())["checkpoint"]
    meta = json.loads((ck / name).read_text())
    with np.load(ck / meta["arrays_file"], allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    return arrays, meta
