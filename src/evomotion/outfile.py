"""Every file evomotion writes goes through here (the one atomic writer).

A write goes to a temporary file in the target's folder, is flushed to disk and renamed over
the target, so a reader, a crash or ``kill -9`` sees the old file or the new one, never a part
(:func:`atomic_write_bytes`; :func:`atomic_output` for writers that need a path, such as a
video encoder or matplotlib). The target must be a new path or a regular file: a device, a
FIFO, a socket or a folder is refused before anything is written (``--naoqi /dev/null`` leaves
``/dev/null`` alone), and so is a folder that does not exist, unless the caller asks for it to
be made (the run loop's own sub-folders). A full disk, a read-only file system or a missing
permission is one :class:`WriteError` line naming the path; the temporary file is removed.

Commands call :func:`check_target` on every path the user names *before* their work starts
(a video after a minute of simulation must not fail for a missing folder).

A file written inside a run folder (one holding :data:`RUN_MARKER` at most three folders up) is
recorded in that marker as the run's own, so that ``--overwrite`` removes only what runs wrote
(:mod:`evomotion.run.folder`).
"""

from __future__ import annotations

import contextlib
import errno
import json
import math
import numbers
import os
import stat
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from evomotion.errors import InputError
from evomotion.textio import kind_of, read_json

#: the file that makes a folder a run folder; it lists the top-level names runs wrote there
RUN_MARKER = ".evomotion-run"
_MARKER_DEPTH = 4  # the target's folder and up to three above it
_UMASK = os.umask(0o022)
os.umask(_UMASK)  # read once: new files get 0666 & ~umask, as open() gives them

#: test hooks, called as ``hook(event, path)`` with event ``"begin"`` (nothing written yet),
#: ``"written"`` (the temporary file is complete, the rename has not happened) or
#: ``"append"`` (before a line is appended to a log or table)
WRITE_HOOKS: list[Callable[[str, Path], None]] = []

_REASONS = {errno.ENOSPC: "no space left on the device", errno.EDQUOT: "disk quota exceeded",
            errno.EROFS: "read-only file system", errno.EACCES: "permission denied",
            errno.EPERM: "operation not permitted", errno.ENOENT: "its folder does not exist",
            errno.ENOTDIR: "a part of the path is not a folder",
            errno.ENAMETOOLONG: "the name is too long", errno.EISDIR: "it is a folder"}


class WriteError(InputError):
    """A file could not be written; ``str()`` is one line naming the path and why."""


def reason(e: BaseException) -> str:
    """A short, one-line reason for an ``OSError`` (or other exception)."""
    if isinstance(e, OSError) and e.errno in _REASONS:
        return _REASONS[e.errno]
    text = getattr(e, "strerror", None) or str(e) or type(e).__name__
    return " ".join(str(text).split())


def check_target(path: str | Path, what: str = "output file", mkdir: bool = False) -> Path:
    """``path`` as a :class:`Path` if it can be written: a new name in an existing, writable
    folder (made when ``mkdir``) or an existing regular file; else one :class:`WriteError`."""
    path = Path(path)
    try:
        st = os.stat(path)  # follows a link: a link to /dev/null is a device
    except FileNotFoundError:
        st = None
    except (OSError, ValueError) as e:
        raise WriteError(f"{path}: cannot write the {what} ({reason(e)})") from None
    if st is not None:
        kind = kind_of(st.st_mode)
        if kind is not None:
            raise WriteError(f"{path}: expected a regular file or a new name for the {what}, "
                             f"found {kind}")
    folder = path.parent
    if mkdir:
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise WriteError(f"{folder}: cannot make the folder for the {what} "
                             f"({reason(e)})") from None
    if not folder.is_dir():
        raise WriteError(f"{path}: the folder {folder} does not exist (make it first)")
    if not os.access(folder, os.W_OK | os.X_OK):
        try:
            read_only = bool(os.statvfs(folder).f_flag & os.ST_RDONLY)
        except OSError:
            read_only = False
        why = errno.EROFS if read_only else errno.EACCES
        raise WriteError(f"{path}: cannot write the {what} ({_REASONS[why]} in {folder})")
    return path


def atomic_write_bytes(path: str | Path, data: bytes, what: str = "file",
                       mkdir: bool = False) -> Path:
    """Replace ``path`` by ``data`` atomically (see the module); its :class:`Path`."""
    with atomic_output(path, what, mkdir) as tmp, open(tmp, "wb") as fh:
        fh.write(data)
    return Path(path)


def atomic_write_text(path: str | Path, text: str, what: str = "file",
                      mkdir: bool = False) -> Path:
    return atomic_write_bytes(path, text.encode("utf-8"), what, mkdir)


@contextlib.contextmanager
def atomic_output(path: str | Path, what: str = "file", mkdir: bool = False,
                  suffix: str = ".tmp") -> Iterator[Path]:
    """A temporary path next to ``path`` for the block to write; on success it replaces
    ``path`` (made durable), on any failure it is removed. ``suffix`` lets a writer that
    chooses its format by extension see one (``".tmp.mp4"``)."""
    run_dir = run_folder_of(path) if mkdir else None
    if run_dir is not None and not _top(path, run_dir).exists():
        # a folder this write makes is claimed before it is made: a kill between the two
        # must not leave it there unclaimed (its resume finds it and claims nothing)
        claim(path, run_dir, made_folder=True)
    path = check_target(path, what, mkdir)
    for hook in WRITE_HOOKS:
        hook("begin", path)
    try:
        st = os.stat(path) if path.exists() else None
        fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name[:80]}.",
                                    suffix=suffix)
        try:  # mkstemp's 0600 -> the mode the file had, or the umask's (what open() gives)
            os.fchmod(fd, stat.S_IMODE(st.st_mode) if st is not None else 0o666 & ~_UMASK)
        finally:
            os.close(fd)
    except OSError as e:
        raise WriteError(f"{path}: cannot write the {what} ({reason(e)})") from None
    tmp = Path(name)
    try:
        yield tmp
        _fsync_file(tmp)
        for hook in WRITE_HOOKS:
            hook("written", path)
        check_target(path, what)  # nothing else took the name meanwhile (a FIFO, say)
        os.replace(tmp, path)
    except OSError as e:
        tmp.unlink(missing_ok=True)
        raise WriteError(f"{path}: cannot write the {what} ({reason(e)})") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    _fsync_dir(path.parent)
    claim(path)  # a file directly in a run folder (a folder this made is claimed above)


def open_append(path: str | Path, what: str = "file", binary: bool = False):
    """``path`` opened for appending (created if new), refusing anything but a regular file
    without blocking on a FIFO; failures are one :class:`WriteError` line."""
    path = Path(path)
    try:
        fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NONBLOCK
                     | os.O_NOFOLLOW, 0o666)
    except OSError as e:
        if e.errno == errno.ENXIO:  # a FIFO nobody reads
            raise WriteError(f"{path}: expected a regular file for the {what}, found a "
                             "FIFO") from None
        if e.errno == errno.ELOOP:  # a link: appending would write where it points
            raise WriteError(f"{path}: expected a regular file for the {what}, found a "
                             "link") from None
        raise WriteError(f"{path}: cannot write the {what} ({reason(e)})") from None
    kind = kind_of(os.fstat(fd).st_mode)
    if kind is not None:
        os.close(fd)
        raise WriteError(f"{path}: expected a regular file for the {what}, found {kind}")
    return os.fdopen(fd, "ab") if binary else os.fdopen(fd, "a", encoding="utf-8",
                                                        newline="")


def append_bytes(path: str | Path, data: bytes, what: str = "file") -> None:
    """Append ``data`` to the regular file ``path`` (see :func:`open_append`); a full disk
    is one :class:`WriteError` line."""
    for hook in WRITE_HOOKS:
        hook("append", Path(path))
    try:
        with open_append(path, what, binary=True) as fh:
            fh.write(data)
    except WriteError:
        raise
    except OSError as e:
        raise WriteError(f"{path}: cannot write the {what} ({reason(e)})") from None


def append_text(path: str | Path, text: str, what: str = "file") -> None:
    append_bytes(path, text.encode("utf-8"), what)


def truncate_file(path: str | Path, offset: int, what: str = "file") -> None:
    """Cut the regular file ``path`` back to ``offset`` bytes (never longer: a file already
    shorter is left alone, not padded with zeros)."""
    with open_append(path, what, binary=True) as fh:
        if os.fstat(fh.fileno()).st_size > offset:
            try:
                os.ftruncate(fh.fileno(), offset)
            except OSError as e:
                raise WriteError(f"{path}: cannot cut the {what} back ({reason(e)})") from None


def save_figure(fig, path: str | Path, what: str = "figure", mkdir: bool = False,
                **savefig_kwargs) -> Path:
    """A matplotlib figure written atomically to ``path`` (format from its suffix), the same
    bytes every time for the same figure (no date in SVG or PDF, fixed SVG ids)."""
    import io

    import matplotlib

    path = check_target(path, what, mkdir)
    fmt = path.suffix.lstrip(".").lower() or "png"
    meta = {"svg": {"Date": None}, "pdf": {"CreationDate": None, "ModDate": None}}.get(fmt)
    buf = io.BytesIO()
    with matplotlib.rc_context({"svg.hashsalt": "evomotion"}):
        fig.savefig(buf, format=fmt, metadata=meta, **savefig_kwargs)
    return atomic_write_bytes(path, buf.getvalue(), what, mkdir)


def write_json(path: str | Path, obj: object, what: str = "JSON file", mkdir: bool = False,
               indent: int = 2) -> Path:
    """``obj`` as JSON, atomically: numpy arrays and scalars become lists and numbers, and a
    non-finite float ``null`` (JSON has no NaN)."""
    text = json.dumps(json_safe(obj), indent=indent, default=_json_default, allow_nan=False)
    return atomic_write_text(path, text + "\n", what, mkdir)


def json_safe(obj: Any) -> Any:
    """``obj`` with every non-finite float (Python or numpy) as ``None``."""
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [json_safe(v) for v in obj]
    if isinstance(obj, numbers.Real) and not isinstance(obj, numbers.Integral) \
            and not math.isfinite(obj):  # float, numpy's floats
        return None
    return obj


def _json_default(obj: Any) -> Any:
    if hasattr(obj, "tolist") and type(obj).__module__ == "numpy":  # arrays and scalars
        return json_safe(obj.tolist())
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def _fsync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _fsync_dir(folder: Path) -> None:
    """Make a rename in ``folder`` durable (a no-op where folders cannot be synced)."""
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


def run_folder_of(path: str | Path) -> Path | None:
    """The run folder holding ``path`` (a folder with :data:`RUN_MARKER`, the path's own
    folder or up to three above it), or ``None``."""
    folder = Path(path).absolute().parent
    for _ in range(_MARKER_DEPTH):
        if (folder / RUN_MARKER).is_file():
            return folder
        if folder.parent == folder:
            break
        folder = folder.parent
    return None


def read_marker(run_dir: Path) -> dict | None:
    """The run folder's marker (``{"evomotion_run": 1, "study": ..., "files": [...]}``), or
    ``None`` when it is missing, unreadable (a FIFO, 1 MiB or more, not JSON) or not this
    program's."""
    try:
        doc = read_json(Path(run_dir) / RUN_MARKER, "run marker", 1 << 20)
    except InputError:
        return None
    if not isinstance(doc, dict) or doc.get("evomotion_run") != 1:
        return None
    files = doc.get("files")
    if not isinstance(files, list) or not all(isinstance(f, str) for f in files):
        return None
    return doc


def write_marker(run_dir: Path, study: str, files: list[str]) -> None:
    """(Re)write the marker of ``run_dir`` naming ``files`` (top-level names) as the run's;
    a failure is one :class:`WriteError` line naming the marker."""
    doc = {"evomotion_run": 1, "study": study, "files": sorted(set(files))}
    p = Path(run_dir) / RUN_MARKER
    try:
        fd, name = tempfile.mkstemp(dir=run_dir, prefix=f".{RUN_MARKER}.", suffix=".tmp")
    except OSError as e:
        raise WriteError(f"{p}: cannot mark the run folder ({reason(e)})") from None
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(json.dumps(doc, indent=1) + "\n")
        os.replace(name, p)
    except OSError as e:
        Path(name).unlink(missing_ok=True)
        raise WriteError(f"{p}: cannot mark the run folder ({reason(e)})") from None
    except BaseException:
        Path(name).unlink(missing_ok=True)
        raise


def _top(path: str | Path, run_dir: Path) -> Path:
    rel = Path(path).absolute().relative_to(Path(run_dir).absolute())
    return Path(run_dir) / rel.parts[0]


def claim(path: str | Path, run_dir: Path | None = None, made_folder: bool = False) -> None:
    """Record in its run folder's marker that ``path`` was written by this program (no-op
    outside a run folder): its name when it lies directly in the run folder; the top-level
    folder holding it only when this write made that folder (``made_folder``). A file written
    into a folder the user made (``plot --out RUN/analysis/fit``) claims nothing, so
    ``--overwrite`` never takes the user's folder for the run's."""
    run_dir = run_dir if run_dir is not None else run_folder_of(path)
    if run_dir is None:
        return
    try:
        parts = Path(path).absolute().relative_to(Path(run_dir).absolute()).parts
    except ValueError:
        return
    if not parts or (len(parts) > 1 and not made_folder) or parts[0] == RUN_MARKER:
        return
    top = parts[0]
    try:
        with _marker_lock(run_dir):
            doc = read_marker(run_dir)
            if doc is None or top in doc["files"]:
                return
            write_marker(run_dir, str(doc.get("study", "")), [*doc["files"], top])
    except OSError as e:
        raise WriteError(f"{Path(run_dir) / RUN_MARKER}: cannot record {top} as the run's "
                         f"({reason(e)})") from None


@contextlib.contextmanager
def _marker_lock(run_dir: Path) -> Iterator[None]:
    """An exclusive ``flock`` on the run folder itself while its marker is updated (the run
    and, say, the studio or ``evomotion plot`` may claim at once)."""
    import fcntl

    fd = os.open(run_dir, os.O_RDONLY | os.O_DIRECTORY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # releases the lock
