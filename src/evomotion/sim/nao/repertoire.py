"""A NAO step repertoire on disk (written by the ``humanoid-repertoire`` study), read by anyone
who walks with it (its own ``walk-to``, the kick's ``play``).

``repertoire/index.json``: ``{"entries": [{"file": "cell-NNNN.motion", "cell": ..., "objective":
..., "measured": {"dx_m", "dy_m", "dtheta_deg"}, ...}, ...], ...}``; each cell's ``.motion`` is one
step from the ready pose back to the ready pose (so steps chain); ``ready.motion`` goes from the
NAO's initial crouch to the ready pose. ``dx_m``/``dy_m`` are the torso's displacement in the
frame of its start heading (x forward, y left), ``dtheta_deg`` its turn (+ left).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from evomotion.errors import InputError
from evomotion.sim.nao.motion import Motion

INDEX = "index.json"


def read_index(run_or_folder: Path) -> tuple[Path, dict]:
    """``(repertoire folder, index)`` of a run folder (or its ``repertoire/``)."""
    p = Path(run_or_folder)
    folder = p / "repertoire" if (p / "repertoire").is_dir() else p
    path = folder / INDEX
    try:
        index = json.loads(path.read_text(encoding="utf-8"))
        entries = index["entries"]
        for i, e in enumerate(entries):
            values = [e["objective"], *(e["measured"][k] for k in ("dx_m", "dy_m",
                                                                  "dtheta_deg"))]
            if not all(_finite(v) for v in values):
                raise ValueError(f"entry {i}: objective and measured dx_m, dy_m, dtheta_deg "
                                 "must be finite numbers")
            if not isinstance(e["file"], str) or ("cell" in e and not _integer(e["cell"])):
                raise ValueError(f"entry {i}: 'file' must be a string and 'cell' an integer")
    except FileNotFoundError:
        raise InputError(f"{path}: no such file (a humanoid-repertoire run folder holds "
                         "repertoire/index.json)") from None
    except OSError as e:
        raise InputError(f"{path}: cannot be read ({e.strerror or type(e).__name__}; a "
                         "humanoid-repertoire run folder holds repertoire/index.json)") from None
    except (ValueError, KeyError, TypeError, AttributeError, UnicodeDecodeError) as e:
        raise InputError(f"{path}: not a repertoire index ({type(e).__name__}: {e})") from None
    if not entries:
        raise InputError(f"{path}: the repertoire is empty")
    return folder, index


def _finite(v: object) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and np.isfinite(v)


def _integer(v: object) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def is_nao_repertoire(index: dict) -> bool:
    """Was the repertoire evolved for the NAO (its own step, the bundled NAO)? Indexes
    written before ``is_nao`` existed name their robot only (and were all the NAO's)."""
    flag = index.get("is_nao")
    return flag if isinstance(flag, bool) else index.get("robot", "nao") == "nao"


def read_cell(folder: Path, entry: dict, joints: tuple[str, ...] | None = None) -> Motion:
    """The motion of an index entry (``joints``: another robot's channels, default the
    NAO's joints)."""
    from evomotion.sim.nao.motion import read_motion

    name = Path(str(entry["file"])).name  # no path outside the folder
    return read_motion(folder / name, joints)


def chain(motions: list[Motion]) -> Motion:
    """Motions that end and start in the same pose, one after the other (each later one
    without its first pose, its times shifted to start where the previous one ended)."""
    times, poses, end = [], [], 0
    for i, m in enumerate(motions):
        t = np.asarray(m.times_ms, dtype=np.int64)
        q = np.asarray(m.values, dtype=float)
        if i:
            t, q = t[1:] - t[0] + end, q[1:]
        times.append(t)
        poses.append(q)
        end = int(t[-1])
    return Motion(motions[0].joints, np.concatenate(times), np.concatenate(poses))
