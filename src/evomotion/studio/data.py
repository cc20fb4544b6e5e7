"""The studio's data layer: run folders read without a server (and fast enough for hundreds).

A run's **status** comes from its files only. ``run.lock`` names the process that writes the
run (pid, start time, host; :mod:`evomotion.run.lock`): *running* when that process is alive
and verifiably that run; *remote* when it is on another host (not checked, never signalled
from here); *stale* when the pid is gone or now belongs to another process (a run killed
with ``kill -9``; resumable from its checkpoints); *unverified* when an older lock (no start
time) names a live ``evomotion`` process. Without a lock, the last of the log's ``stopped:
REASON`` / ``run failed`` / ``resumed`` lines decides: *finished* (with its stop reason),
*interrupted* (``stopped: interrupted``, or a run that never logged its end) or *failed*.

Every read is bounded and never blocks (:mod:`.readers`: a FIFO or a device is read as
missing, a file only in its head and tail), and :func:`list_runs` gives each folder
:data:`SUMMARY_TIMEOUT_S` on a worker thread: a folder that does not answer is listed as
*unreadable (timed out)*, so listing 200 runs of 1,000 generations reads a few kilobytes per
run and one hostile folder cannot hold the list up.
"""

from __future__ import annotations

import contextlib
import csv
import math
import os
import tomllib
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.errors import InputError
from evomotion.run.config import RENAMED_STUDIES, config_from_run_dir
from evomotion.run.lock import LOCK_NAME, LockOwner, owner_state
from evomotion.run.lock import lock_owner as read_lock_owner
from evomotion.run.stats import step_values
from evomotion.studio import readers
from evomotion.studio.readers import head_tail, one_line
from evomotion.studio.tags import read_tags

TAIL_BYTES = 16384
#: how deep below RUNS_DIR run folders are looked for (experiments nest their runs)
MAX_DEPTH = 3
#: the time one run folder gets to be summarised in :func:`list_runs`
SUMMARY_TIMEOUT_S = 2.0
#: the largest config.toml shown
MAX_CONFIG_BYTES = 1 << 20
#: the statuses a run can be resumed from (with checkpoints)
RESUMABLE = ("interrupted", "stale")
STATUSES = ("running", "remote", "stale", "unverified", "finished", "interrupted", "failed",
            "unreadable")


@dataclass(frozen=True)
class RunSummary:
    name: str  # the path below RUNS_DIR, with '/'
    study: str
    status: str  # one of STATUSES
    stop_reason: str
    generation: int
    evaluations: int
    best: float
    started: float  # epoch seconds (config.toml written at the start)
    duration_s: float
    resumable: bool
    pid: int | None
    tags: tuple[str, ...] = ()  # tags.txt (studio/tags.py)

    def row(self) -> dict[str, Any]:
        """The summary as JSON-safe values (non-finite numbers are ``None``)."""
        d = asdict(self)
        for k in ("best", "started", "duration_s"):
            d[k] = float(d[k]) if math.isfinite(d[k]) else None
        return d


def find_runs(root: Path) -> list[Path]:
    """Every run folder (one holding ``config.toml``) below ``root``, newest first."""
    root = Path(root)
    out: list[Path] = []

    def walk(d: Path, depth: int) -> None:
        try:
            entries = list(os.scandir(d))
        except OSError:
            return
        names = {e.name for e in entries}
        if "config.toml" in names and d != root:
            out.append(d)
            return
        if depth < MAX_DEPTH:
            for e in entries:
                try:
                    is_dir = e.is_dir(follow_symlinks=False)
                except OSError:
                    continue
                if is_dir and not e.name.startswith("."):
                    walk(Path(e.path), depth + 1)

    walk(root, 0)
    return sorted(out, key=_started, reverse=True)


def _started(d: Path) -> float:
    try:
        t = (d / "config.toml").stat().st_mtime
    except (OSError, ValueError):
        return 0.0
    return t if math.isfinite(t) else 0.0


def lock_state(run_dir: Path) -> tuple[LockOwner | None, str]:
    """The owner ``run.lock`` names (``None``: none, or nothing readable) and its state:
    ``none | running | stale | remote | unknown`` (:func:`evomotion.run.lock.owner_state`)."""
    owner = read_lock_owner(run_dir)
    return owner, owner_state(owner, Path(run_dir) / LOCK_NAME)  # a run from Python too


def _log_status(run_dir: Path) -> tuple[str, str]:
    _, tail = head_tail(run_dir / "log.txt", TAIL_BYTES)
    for line in reversed(tail.splitlines()):
        if line.startswith("stopped: "):
            reason = one_line(line[9:].split(" at generation")[0], 160)
            return ("interrupted" if reason == "interrupted" else "finished"), reason
        if line.startswith("run failed"):
            return "failed", one_line(line, 160)
        if line.startswith(("resumed at", "run ")):
            break
    return "interrupted", "no end logged"


def run_status(run_dir: Path) -> tuple[str, str, int | None]:
    """``(status, detail, pid)`` of a run folder (see the module docstring); ``pid`` only
    for a run that is verifiably running here."""
    owner, state = lock_state(run_dir)
    if owner is not None:
        who = f"pid {owner.pid} on {one_line(owner.host, 80)}"
        if state == "running":
            return "running", "", owner.pid
        if state == "remote":
            return "remote", f"lock held by {who}, another host: not checked or stopped " \
                             "from here", None
        if state == "stale":
            return "stale", f"stale lock: {who} is gone or is another process", None
        if state == "unknown":
            return "unverified", f"lock names {who}: alive, but not verifiable as this " \
                                 "run (a lock without a start time)", None
    return (*_log_status(run_dir), None)


def is_resumable(run_dir: Path, status: str) -> bool:
    return status in RESUMABLE and (run_dir / "checkpoints").is_dir()


def last_stats_row(path: Path) -> dict[str, str]:
    """The last complete row of ``stats.csv`` as text cells ({} if none)."""
    header, tail = head_tail(path, 8192)
    if not header:
        return {}
    lines = tail.split("\n")
    lines = [ln for ln in lines[:-1] if ln]  # the last piece may be a row being written
    if not lines or lines[-1] == header:
        return {}
    cols = header.split(",")
    try:
        cells = next(csv.reader([lines[-1]]))
    except (csv.Error, StopIteration):
        return {}
    return dict(zip(cols, cells, strict=False))


def _num(v: Any, default: float = float("nan")) -> float:
    try:
        return float(v)
    except (TypeError, ValueError, OverflowError):
        return default


def _int(v: Any, default: int) -> int:
    x = _num(v)
    return int(x) if math.isfinite(x) and abs(x) < 2**53 else default


def study_name(run_dir: Path) -> str:
    """The ``study = "..."`` line of ``config.toml`` (read without parsing the file; a name a
    study had before a rename, :data:`~evomotion.run.config.RENAMED_STUDIES`, parses it to
    tell which study it is now)."""
    first, _ = head_tail(run_dir / "config.toml", 0)
    if first.startswith("study"):
        name = first.partition("=")[2].strip().strip('"')
        if any(name == old for old, _, _ in RENAMED_STUDIES):  # renamed since: parse it
            with contextlib.suppress(InputError, OSError):
                name = config_from_run_dir(run_dir)[0]
        return one_line(name, 80)
    return "?"


def summarize(root: Path, run_dir: Path) -> RunSummary:
    status, reason, pid = run_status(run_dir)
    row = last_stats_row(run_dir / "stats.csv")
    return RunSummary(
        name=run_dir.relative_to(root).as_posix(), study=study_name(run_dir), status=status,
        stop_reason=reason, generation=_int(row.get("generation"), -1),
        evaluations=_int(row.get("evaluations"), 0), best=_num(row.get("best_so_far")),
        started=_started(run_dir), duration_s=_num(row.get("wall_s"), 0.0),
        resumable=is_resumable(run_dir, status), pid=pid, tags=read_tags(run_dir))


def unreadable(name: str, why: str) -> RunSummary:
    """The row of a folder that could not be summarised."""
    return RunSummary(name=name, study="?", status="unreadable", stop_reason=one_line(why, 160),
                      generation=-1, evaluations=0, best=float("nan"), started=0.0,
                      duration_s=0.0, resumable=False, pid=None)


def list_runs(root: Path, study: str | None = None,
              timeout_s: float | None = None) -> list[RunSummary]:
    """A summary per run folder below ``root`` (newest first), each folder given
    ``timeout_s`` (default :data:`SUMMARY_TIMEOUT_S`) on a worker thread."""
    root = Path(root)
    dirs = find_runs(root)
    calls, bad = [], {}
    for d in dirs:
        name = d.relative_to(root).as_posix()
        try:
            readers.check_name(name, "run folder")
        except InputError:
            bad[d] = one_line(os.fsencode(name).decode("utf-8", "replace"), 160)
            continue
        calls.append((str(d.absolute()), summarize, (root, d)))
    done = readers.timed(calls, SUMMARY_TIMEOUT_S if timeout_s is None else timeout_s)
    runs = []
    for d in dirs:
        if d in bad:
            runs.append(unreadable(bad[d], "the folder's name is not valid text"))
            continue
        kind, value = done[str(d.absolute())]
        if kind == "ok":
            runs.append(value)
        else:
            why = "timed out" if kind == "timeout" else f"{type(value).__name__}: {value}"
            runs.append(unreadable(d.relative_to(root).as_posix(), why))
    return [r for r in runs if study in (None, "", r.study)]


def _resolved(root: Path, rel: object, what: str) -> Path:
    rel = readers.check_name(rel, what)
    base = Path(root).resolve()
    try:
        path = (base / rel).resolve()
    except (OSError, ValueError, RuntimeError):  # RuntimeError: a symbolic link loop
        raise InputError(f"{one_line(rel, 120)}: no such {what} under {root}") from None
    if not path.is_relative_to(base):
        raise InputError(f"{one_line(rel, 120)}: no such {what} under {root}")
    return path


def resolve_run(root: Path, name: str) -> Path:
    """The run folder ``name`` below ``root`` (one holding an entry ``config.toml``, as
    :func:`find_runs` lists it, however unreadable); an :class:`InputError` for anything
    outside it, not a run folder, or not a valid name (no path outside RUNS_DIR is read)."""
    path = _resolved(root, name, "run")
    if path == Path(root).resolve() or not os.path.lexists(path / "config.toml"):
        raise InputError(f"{one_line(name, 120)}: not a run folder under {root}")
    return path


def safe_file(root: Path, rel: str) -> Path:
    """A regular file below ``root`` (symbolic links resolved; nothing outside ``root``)."""
    path = _resolved(root, rel, "file")
    if not path.is_file():
        raise InputError(f"{one_line(rel, 120)}: no such file under {root}")
    return path


def read_config(run_dir: Path) -> tuple[str, dict[str, Any]]:
    """The text of ``config.toml`` and its table ({} when it does not parse); the text is
    the error line when the file cannot be read."""
    from evomotion.textio import read_file_bytes

    try:
        text = read_file_bytes(run_dir / "config.toml", "config file", MAX_CONFIG_BYTES
                               ).decode("utf-8", "replace")
    except InputError as e:
        return f"error: {one_line(e)}", {}
    try:
        return text, tomllib.loads(text)
    except (tomllib.TOMLDecodeError, RecursionError, ValueError):
        return text, {}


def log_tail(run_dir: Path, lines: int = 40) -> list[str]:
    _, tail = head_tail(run_dir / "log.txt", TAIL_BYTES)
    return tail.splitlines()[-lines:]


class StatsTail:
    """``stats.csv`` read incrementally: :meth:`update` parses only the bytes appended since the
    last call (and starts again when the file was cut back by a resume). At most
    :attr:`CHUNK` bytes are read per call and :attr:`MAX_BYTES` / :attr:`MAX_CELLS` in all
    (then :attr:`full` is set and the rest is not read); a FIFO or device reads as empty."""

    CHUNK = 4 << 20
    MAX_BYTES = 32 << 20
    MAX_CELLS = 4_000_000

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self.offset = 0
        self.cells = 0
        self.full = False
        self.columns: list[str] = []
        self.rows: list[list[float]] = []

    def _reset(self) -> None:
        self.offset, self.cells, self.full, self.rows, self.columns = 0, 0, False, [], []

    def update(self) -> int:
        """Read what was appended; the number of new rows."""
        chunk, size = readers.read_range(self.path, self.offset, 0 if self.full else self.CHUNK)
        if size < self.offset:
            self._reset()
            chunk, size = readers.read_range(self.path, 0, self.CHUNK)
        if not chunk:
            return 0
        end = chunk.rfind(b"\n") + 1  # a half-written last row waits for the next call
        if end == 0:
            self.full = len(chunk) >= self.CHUNK  # a "row" longer than a chunk: give up
            return 0
        text = chunk[:end].decode("utf-8", "replace")
        self.offset += end
        lines = text.splitlines()
        if not self.columns and lines:
            self.columns = lines.pop(0).split(",")[:1000]
        new = []
        try:
            for cells in csv.reader(lines):
                new.append([_num(c) for c in cells[:len(self.columns)]])
        except csv.Error:
            pass
        self.cells += sum(map(len, new))
        self.full = self.offset >= self.MAX_BYTES or self.cells >= self.MAX_CELLS
        self.rows.extend(new)
        return len(new)

    def column(self, name: str, start: int = 0) -> list[float | None]:
        if name not in self.columns:
            return []
        j = self.columns.index(name)
        return [None if not np.isfinite(r[j]) else r[j] for r in self.rows[start:]
                if len(r) > j]

    def last(self, name: str) -> float | None:
        """The last row's value of column ``name`` (None: missing or not finite)."""
        if name not in self.columns or not self.rows:
            return None
        j, row = self.columns.index(name), self.rows[-1]
        return row[j] if len(row) > j and np.isfinite(row[j]) else None

    def array(self, name: str) -> np.ndarray:
        return np.array([v if v is not None else np.nan for v in self.column(name)], float)


def best_curve(run_dir: Path) -> tuple[np.ndarray, np.ndarray]:
    """(evaluations, best so far) of the run's ``stats.csv`` rows where both are finite."""
    st = StatsTail(run_dir / "stats.csv")
    st.update()
    e, b = st.array("evaluations"), st.array("best_so_far")
    ok = np.isfinite(e) & np.isfinite(b)
    return e[ok], b[ok]


def compare_groups(run_dirs: list[Path], points: int = 200,
                   labels: list[str] | None = None, group_of: Any = None) -> list[dict]:
    """The runs grouped by study (their fitnesses are on different scales, so runs of
    different studies are never pooled; issue 35): per study, in the order first selected,
    ``{"study", "names": [run names], **compare_runs(its runs), "curves": [{"run", "evaluations",
    "best"}]}`` with each run's own best-so-far curve (finite rows only); ``labels``: the
    runs' names (default their folder names); ``group_of(run_dir)``: a finer group label
    that includes the study (``studio/compare.py``; default the study)."""
    names = dict(zip(run_dirs, labels or [d.name for d in run_dirs], strict=True))
    groups: dict[str, list[Path]] = {}
    for d in run_dirs:
        groups.setdefault((group_of or study_name)(d), []).append(d)
    out = []
    for study, dirs in groups.items():
        curves = []
        for d in dirs:
            e, b = best_curve(d)
            curves.append({"run": names[d], "evaluations": e.tolist(), "best": b.tolist()})
        out.append({"study": study, "names": [names[d] for d in dirs],
                    **compare_runs(dirs, points), "curves": curves})
    return out


def compare_runs(run_dirs: list[Path], points: int = 200) -> dict[str, list[float]]:
    """Median and interquartile band of the best-so-far fitness of ``run_dirs`` against
    evaluations, on a common grid (a run counts at x once it has made x evaluations and until
    its last row)."""
    curves = [c for c in map(best_curve, run_dirs) if c[0].size]
    if not curves:
        return {"evaluations": [], "median": [], "q25": [], "q75": [], "runs": []}
    hi = max(c[0][-1] for c in curves)
    lo = min(c[0][0] for c in curves)
    x = np.unique(np.linspace(lo, hi, points).round())
    Y = np.array([step_values(x, e, b, hold=False) for e, b in curves])
    have = np.isfinite(Y).any(0)
    x, Y = x[have], Y[:, have]
    q25, med, q75 = np.nanpercentile(Y, [25, 50, 75], axis=0)
    return {"evaluations": x.tolist(), "median": med.tolist(), "q25": q25.tolist(),
            "q75": q75.tolist(), "runs": np.isfinite(Y).sum(0).tolist()}


#: what a run writes all the time and no study view shows (their changes do not redraw it)
NOT_VIEWED = frozenset({"stats.csv", "log.txt", "run.lock", "checkpoints", "population.bin",
                        "studio-stderr.txt"})


def artifact_signature(run_dir: Path, limit: int = 2000) -> tuple:
    """The names, sizes and modification times of the run's artifacts (its folder and one level
    of subfolders, at most ``limit`` entries, without :data:`NOT_VIEWED`): the run page redraws
    its study view when this changes (a ``best.motion`` written at the end of a run showed only
    after a reload; issue 35). Unreadable entries are left out."""
    out: list[tuple] = []

    def scan(folder: Path, prefix: str, deeper: bool) -> None:
        try:
            with os.scandir(folder) as it:
                for e in it:
                    if len(out) >= limit:
                        return
                    if e.name in NOT_VIEWED or e.name.startswith("."):
                        continue
                    try:
                        st = e.stat(follow_symlinks=False)
                    except OSError:
                        continue
                    out.append((prefix + e.name, st.st_size, st.st_mtime_ns))
                    if deeper and e.is_dir(follow_symlinks=False):
                        scan(Path(e.path), prefix + e.name + "/", False)
        except OSError:
            return

    scan(Path(run_dir), "", True)
    return tuple(sorted(out))
