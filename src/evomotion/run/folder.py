"""Run folders: made, marked as a run's own, emptied only of what runs wrote.

A run folder carries :data:`~evomotion.outfile.RUN_MARKER`, written when a run starts in an
empty folder; it lists the top-level names runs wrote there (the run loop's files at the start,
and every file written through :mod:`evomotion.outfile` after). ``--overwrite`` removes only
those, and refuses a folder holding anything else, naming it: a folder that merely holds a
``config.toml`` beside a thesis is never emptied.
"""

from __future__ import annotations

import os
import re
import stat
import tempfile
import time
from pathlib import Path

from evomotion.errors import InputError
from evomotion.outfile import (
    RUN_MARKER,
    WriteError,
    kind_of,
    read_marker,
    reason,
    write_marker,
)
from evomotion.run.checkpoint import NAME
from evomotion.run.lock import LOCK_NAME

RUN_MARKERS = ("config.toml", "stats.csv", "checkpoints")
#: what the run loop itself writes in every run folder (recorded in the marker when a run starts)
#: (a study's own files, e.g. physics.json or best.motion, are claimed as they are written)
RUN_FILES = ("config.toml", "stats.csv", "log.txt", "checkpoints", "run.lock", "best.json",
             "plots", "population.bin", "archive.npz")
_SHOWN = 5


def holds_run(path: Path) -> bool:
    """Whether ``path`` already holds (part of) a run: a run's config, stats or checkpoints."""
    return any((path / m).exists() for m in RUN_MARKERS)


def is_run_folder(path: Path) -> bool:
    """Whether ``path`` carries the marker a run writes (:data:`RUN_MARKER`)."""
    return read_marker(Path(path)) is not None


def make_run_dir(study: str, out: Path | str | None = None, root: Path | str = "runs") -> Path:
    """``out`` if given (created), else ``runs/<study>-<YYYYmmdd-HHMMSS>[-N]``; every problem
    creating it is one :class:`InputError` line. (Whether the folder may take a new run is
    the run loop's check, under the folder's lock: :func:`prepare_new_run`.)"""
    if out is not None:
        path = Path(out)
    else:
        stamp = time.strftime("%Y%m%d-%H%M%S")
        path = Path(root) / f"{study}-{stamp}"
        n = 1
        while path.exists():
            n += 1
            path = Path(root) / f"{study}-{stamp}-{n}"
    try:
        exists = path.exists() or path.is_symlink()
    except (OSError, ValueError) as e:
        raise InputError(f"--out {path}: cannot use the run folder ({reason(e)})") from None
    if exists and not path.is_dir():
        raise InputError(f"--out {path}: expected a folder, found "
                         f"{kind_of(os.stat(path).st_mode) or 'a file'}"
                         if path.exists() else f"--out {path}: expected a folder, found a "
                         "dangling link")
    try:
        path.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=path, prefix=".write-test.", suffix=".tmp")
        os.close(fd)
        os.unlink(probe)
    except (OSError, ValueError) as e:
        raise InputError(f"--out {path}: cannot create the run folder "
                         f"({reason(e)})") from None
    return path


#: the one writer's temporary names: ``.NAME.`` + 8 random characters (tempfile) + ``.tmp``
_TEMPORARY = re.compile(r"\..+\.[a-z0-9_]{8}\.tmp(\.[A-Za-z0-9]{1,8})?")


def make_output_folder(label: str, out: Path | str | None, option: str = "--out") -> Path:
    """A folder for a command's several outputs (an experiment's tables and plots): ``out``
    (made if missing, but its parent must exist: a mistyped path makes no folders) or a new
    ``runs/<label>-<time>``. It must be new, empty, or a folder this program marked as its own
    that holds nothing else (its earlier outputs are replaced); it is marked, so that what the
    command writes there is recorded as its own. A folder holding anything else (a project
    beside a thesis) is refused, naming what it holds, and nothing is written in it."""
    if out is not None:
        out = Path(out)
        if not out.is_dir() and not out.absolute().parent.is_dir():
            raise WriteError(f"{option} {out}: the folder {out.absolute().parent} does not "
                             "exist (make it first)")
        if out.is_dir():
            foreign = foreign_entries(out)
            if foreign:
                raise InputError(f"{option} {out}: the folder holds files this program did not "
                                 f"write ({_names(foreign)}); choose a new or empty folder")
    path = make_run_dir(label, out)
    if not is_run_folder(path):
        write_marker(path, label, [])
    return path


def _is_temporary(name: str) -> bool:
    """A temporary file of the one writer (``.NAME.XXXX.tmp``, or ``.tmp.mp4`` and such for
    writers that choose their format by the extension)."""
    return _TEMPORARY.fullmatch(name) is not None


def _listing(path: Path) -> list[str]:
    try:
        return sorted(p.name for p in path.iterdir())
    except OSError as e:
        raise InputError(f"{path}: cannot list the folder ({reason(e)})") from None


def foreign_entries(path: Path) -> list[str]:
    """The entries of ``path`` that no run wrote: not named in its marker (every entry, when
    there is no marker), other than the lock, the marker and temporary files."""
    doc = read_marker(path)
    own = set(doc["files"]) if doc is not None else set()
    ours = {RUN_MARKER} | ({LOCK_NAME} if doc is not None or _our_lock(path) else set())
    return [n for n in _listing(path) if n not in own and n not in ours
            and not _is_temporary(n)]


def _our_lock(path: Path) -> bool:
    """``run.lock`` is a regular file (not a link) that is empty or names an owner in this
    program's format: a lock of ours, not a user's file of that name."""
    from evomotion.run.lock import parse_owner

    p = path / LOCK_NAME
    try:
        st = os.lstat(p)
        if not stat.S_ISREG(st.st_mode) or st.st_size > 4096:
            return False
        text = p.read_bytes().decode("utf-8", "replace")
    except OSError:
        return False
    return not text.strip() or parse_owner(text) is not None


def _names(names: list[str]) -> str:
    more = f" and {len(names) - _SHOWN} more" if len(names) > _SHOWN else ""
    return ", ".join(names[:_SHOWN]) + more


def check_new_run(path: Path, overwrite: bool = False) -> None:
    """Refuse (one :class:`InputError` line, nothing touched) a folder that cannot take a new
    run: one holding anything no run wrote, or (unless ``overwrite``) a run."""
    path = Path(path)
    if not path.exists():
        return
    marked = is_run_folder(path)
    foreign = foreign_entries(path)
    if foreign:
        if not marked and (path / "config.toml").is_file() and (path / "checkpoints").is_dir():
            raise InputError(f"{path}: the folder holds a run written before run folders were "
                             f"marked ({RUN_MARKER}); continue it with 'evomotion resume "
                             f"{path}', or choose another --out (--overwrite only empties "
                             "folders a run marked as its own; nothing was deleted)")
        what = "--overwrite removes only what runs wrote" if overwrite else \
            "a new run needs an empty or new folder"
        raise InputError(f"{path}: the folder holds files no run wrote ({_names(foreign)}); "
                         f"{what}, so nothing was deleted: choose another --out")
    if holds_run(path) and not overwrite:
        raise InputError(f"{path}: the folder already holds a run; continue it with "
                         f"'evomotion resume {path}' or start it again with --overwrite")


def check_resumable(path: Path) -> None:
    """Refuse (one line, nothing touched) a folder ``evomotion resume`` must not write to:
    not a run folder (neither the marker nor the run loop's config.toml and checkpoints/ of a
    run written before the marker), or without a checkpoint."""
    path = Path(path)
    if not path.is_dir():
        raise InputError(f"{path}: no such run folder")
    legacy = (path / "config.toml").is_file() and (path / "checkpoints").is_dir()
    if not (is_run_folder(path) or legacy):
        raise InputError(f"{path}: not a run folder (no {RUN_MARKER}, config.toml or "
                         "checkpoints/); nothing to resume")
    ck = path / "checkpoints"
    try:
        found = ck.is_dir() and any(NAME.fullmatch(p.name) for p in ck.iterdir())
    except OSError as e:
        raise InputError(f"{ck}: cannot list the checkpoints ({reason(e)})") from None
    if not found:
        raise InputError(f"{path}: no checkpoint to resume from (checkpoints/ holds none)")


def prepare_new_run(path: Path, study: str, overwrite: bool = False) -> None:
    """Make the (locked) folder ``path`` ready for a new run of ``study``: it must be empty,
    or be a run folder (marker) that holds nothing but what runs wrote there; one that holds a
    run is refused unless ``overwrite``, which then removes only what runs wrote. Anything
    else in the folder is named in a one-line :class:`InputError`, and nothing is deleted."""
    path = Path(path)
    check_new_run(path, overwrite)
    if holds_run(path):
        _remove_own(path)
    doc = read_marker(path)
    kept = [n for n in (doc["files"] if doc else []) if (path / n).exists()]
    write_marker(path, study, [*kept, *RUN_FILES])


def _remove_own(path: Path) -> None:
    """Remove what the marker names (links as links, never what they point at) and temporary
    files; the lock and the marker stay."""
    import shutil

    doc = read_marker(path)
    assert doc is not None, "only a marked run folder is emptied"
    own = set(doc["files"])
    for name in _listing(path):
        if name in (LOCK_NAME, RUN_MARKER) or not (name in own or _is_temporary(name)):
            continue
        child = path / name
        try:
            if child.is_dir() and not child.is_symlink():
                shutil.rmtree(child)
            else:
                child.unlink()
        except OSError as e:
            raise WriteError(f"{child}: cannot remove it for --overwrite ({reason(e)})"
                             ) from None


def clean_temporaries(run_dir: Path, depth: int = 4) -> int:
    """Remove the temporary files interrupted atomic writes left in the run folder (and its
    folders, ``depth`` levels down, links not followed); their number."""
    n = 0
    todo = [(Path(run_dir), 0)]
    while todo:
        d, level = todo.pop()
        try:
            entries = list(os.scandir(d))
        except OSError:
            continue
        for e in entries:
            if e.is_dir(follow_symlinks=False):
                if level + 1 < depth:
                    todo.append((Path(e.path), level + 1))
            elif _is_temporary(e.name) and e.is_file(follow_symlinks=False):
                Path(e.path).unlink(missing_ok=True)
                n += 1
    return n

