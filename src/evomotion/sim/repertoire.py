"""A NAO step repertoire on disk (written by the ``humanoid-repertoire`` study), read by anyone
who walks with it (its own ``walk-to``, the kick's ``play``).

``repertoire/index.json``: ``{"entries": [{"file": "cell-NNNN.motion", "cell": ..., "objective":
..., "measured": {"dx_m", "dy_m", "dtheta_deg"}, ...}, ...], ...}``; each cell's ``.motion`` is one
step from the ready pose back to the ready pose (so steps chain); ``ready.motion`` goes from the
NAO's initial crouch to the ready pose. ``dx_m``/``dy_m`` are the torso's displacement in the
frame of its start heading (x forward, y left), ``dtheta_deg`` its turn (+ left).
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.errors import FileFormatError, InputError
from evomotion.sim.motion import Motion
from evomotion.sim.robots.nao.old_repertoire import old_flag_problem, old_stepper

INDEX = "index.json"
#: the largest index.json read (bytes; a full NAO archive's index is about 1 MiB) and its
#: deepest nesting (this program writes 4 levels)
MAX_INDEX_BYTES = 16 * 1024 * 1024
MAX_INDEX_DEPTH = 8
MAX_ENTRIES = 100_000
#: a step moves the torso at most this far (m) in x or y, and turns at most this much (deg)
MAX_STEP_M = 1.0
MAX_TURN_DEG = 180.0
MAX_OBJECTIVE = 1000.0  # the objective of a step (tilt and effort) lies within +- this
MAX_HOLD_S = 60.0
#: a cell file: a plain name in the repertoire folder (no folder part, no "..")
CELL_FILE = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]{0,250}\.motion$")
#: the step models a repertoire is evolved with (``index.json``'s ``stepper``)
STEPPERS = ("closed_form", "numerical")


def read_index(run_or_folder: Path) -> tuple[Path, dict]:
    """``(repertoire folder, index)`` of a run folder (or its ``repertoire/``): read with the
    bounded JSON reader (size, nesting, finite numbers: a NaN ``hold_s`` is refused) and
    checked field by field (:func:`check_index`); every failure is one line."""
    from evomotion.textio import read_json

    p = Path(run_or_folder)
    folder = p / "repertoire" if (p / "repertoire").is_dir() else p
    path = folder / INDEX
    if not os.path.lexists(path):
        raise InputError(f"{path}: no such file (a humanoid-repertoire run folder holds "
                         "repertoire/index.json)")
    index = read_json(path, "repertoire index", MAX_INDEX_BYTES, MAX_INDEX_DEPTH)
    check_index(index, path)
    return folder, index


def _number(v: object, lo: float, hi: float) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and lo <= v <= hi


def _short(v: object) -> str:
    text = repr(v)
    return text if len(text) <= 60 else text[:57] + "..."


def check_index(index: Any, path: Path) -> None:
    """One :class:`FileFormatError` naming ``path`` unless ``index`` is a repertoire index:
    an object with ``entries`` (1 to :data:`MAX_ENTRIES`), each with a cell ``file`` (a plain
    ``.motion`` name), a non-negative integer ``cell``, an ``objective`` within
    +-:data:`MAX_OBJECTIVE` and ``measured`` ``dx_m``/``dy_m`` within +-:data:`MAX_STEP_M` m and
    ``dtheta_deg`` within +-:data:`MAX_TURN_DEG`; ``hold_s`` (when given) within 0 to
    :data:`MAX_HOLD_S` s, ``robot`` a short printable name, ``stepper`` one of
    :data:`STEPPERS` (an index written before it existed: its old NAO flag true or false)."""
    def bad(expected: str) -> FileFormatError:
        return FileFormatError(path, None, expected)

    if not isinstance(index, dict) or not isinstance(index.get("entries"), list):
        raise bad("expected a repertoire index: an object with a list 'entries'")
    if "hold_s" in index and not _number(index["hold_s"], 0.0, MAX_HOLD_S):
        raise bad(f"expected 'hold_s' a number of seconds from 0 to {MAX_HOLD_S:g}, got "
                  f"{_short(index['hold_s'])}")
    robot = index.get("robot", "nao")
    if not isinstance(robot, str) or not robot.isprintable() or not 0 < len(robot) <= 200:
        raise bad(f"expected 'robot' a printable name, got {_short(robot)}")
    stepper = index.get("stepper", STEPPERS[0])
    if stepper not in STEPPERS:
        raise bad(f"expected 'stepper' one of {', '.join(STEPPERS)}, got {_short(stepper)}")
    old = old_flag_problem(index)
    if old is not None:
        raise bad(old)
    entries = index["entries"]
    if not entries:
        raise bad("the repertoire is empty (no standing step)")
    if len(entries) > MAX_ENTRIES:
        raise bad(f"expected at most {MAX_ENTRIES} entries, got {len(entries)}")
    for i, e in enumerate(entries):
        m = e.get("measured") if isinstance(e, dict) else None
        if not isinstance(m, dict):
            raise bad(f"entry {i}: expected an object with 'file', 'cell', 'objective' and "
                      "'measured'")
        for key, limit, unit in (("dx_m", MAX_STEP_M, "m"), ("dy_m", MAX_STEP_M, "m"),
                                 ("dtheta_deg", MAX_TURN_DEG, "degrees")):
            if not _number(m.get(key), -limit, limit):
                raise bad(f"entry {i}: expected measured {key} a number within +-{limit:g} "
                          f"{unit}, got {_short(m.get(key))}")
        if not _number(e.get("objective"), -MAX_OBJECTIVE, MAX_OBJECTIVE):
            raise bad(f"entry {i}: expected 'objective' a number within +-{MAX_OBJECTIVE:g}, "
                      f"got {_short(e.get('objective'))}")
        f = e.get("file")
        if not isinstance(f, str) or not CELL_FILE.match(f) or ".." in f:
            raise bad(f"entry {i}: expected 'file' a .motion file name in the repertoire "
                      f"folder such as cell-0042.motion, got {_short(f)}")
        c = e.get("cell", 0)
        if not isinstance(c, int) or isinstance(c, bool) or not 0 <= c < 2**31:
            raise bad(f"entry {i}: expected 'cell' a non-negative integer, got {_short(c)}")


def stepper_of(index: dict) -> str:
    """The step model the repertoire was evolved with: ``"closed_form"`` (a robot with the
    ``leg_ik`` capability through its own closed-form step, played by its own replay; the kick
    walks only with these) or ``"numerical"`` (any robot's generic step; played on the model
    its run's ``config.toml`` names). Indexes older than ``stepper``: see
    :mod:`evomotion.sim.robots.nao.old_repertoire`."""
    stepper = index.get("stepper")
    return stepper if isinstance(stepper, str) else old_stepper(index)


def cell_path(folder: Path, name: object) -> Path:
    """The file ``name`` of the repertoire ``folder``: a plain ``.motion`` name (no ``/``, no
    ``..``) whose real path (links followed) lies in the folder; else one line."""
    if not isinstance(name, str) or not CELL_FILE.match(name) or ".." in name:
        raise InputError(f"{folder}: expected a cell file name such as cell-0042.motion, got "
                         f"{_short(name)}")
    path = Path(folder) / name
    real, home = os.path.realpath(path), os.path.realpath(folder)
    if os.path.dirname(real) != home:
        raise InputError(f"{path}: expected a file inside {folder}, it leads to {real}")
    return path


def read_cell(folder: Path, entry: dict, joints: tuple[str, ...] | None = None) -> Motion:
    """The motion of an index entry (``joints``: another robot's channels, default the
    NAO's joints), read with :func:`~evomotion.sim.motion.read_motion` (bounded: a FIFO,
    a device or an oversize file is one line)."""
    from evomotion.sim.motion import read_motion

    return read_motion(cell_path(folder, entry.get("file")), joints)


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
