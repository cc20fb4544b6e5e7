"""The studio's data layer: run folders read without a server (and fast enough for hundreds).

A run's **status** comes from its files only: ``run.lock`` names a live process on this host
-> *running*; it names a process that is gone -> *interrupted* (killed; resumable from its
checkpoints); else the last of the log's ``stopped: REASON`` / ``run failed`` / ``resumed``
lines decides: *finished* (with its stop reason), *interrupted* (``stopped: interrupted``, or a
run that never logged its end) or *failed*. Every reader reads only the head and tail of a
file, so listing 200 runs of 1,000 generations reads a few kilobytes per run.
"""

from __future__ import annotations

import csv
import io
import os
import socket
import tomllib
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.errors import InputError
from evomotion.run.lock import lock_owner as read_lock_owner
from evomotion.run.stats import step_values

TAIL_BYTES = 16384
#: how deep below RUNS_DIR run folders are looked for (experiments nest their runs)
MAX_DEPTH = 3


@dataclass(frozen=True)
class RunSummary:
    name: str  # the path below RUNS_DIR, with '/'
    study: str
    status: str  # running | finished | interrupted | failed
    stop_reason: str
    generation: int
    evaluations: int
    best: float
    started: float  # epoch seconds (config.toml written at the start)
    duration_s: float
    resumable: bool
    pid: int | None

    def row(self) -> dict[str, Any]:
        d = asdict(self)
        d["best"] = None if not np.isfinite(self.best) else float(self.best)
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
                if e.is_dir(follow_symlinks=False) and not e.name.startswith("."):
                    walk(Path(e.path), depth + 1)

    walk(root, 0)
    return sorted(out, key=_started, reverse=True)


def _started(d: Path) -> float:
    try:
        return (d / "config.toml").stat().st_mtime
    except OSError:
        return 0.0


def head_tail(path: Path, n: int = TAIL_BYTES) -> tuple[str, str]:
    """The first line and the last ``n`` bytes of a text file ('' where it is missing)."""
    try:
        with open(path, "rb") as fh:
            first = fh.readline(4096).decode("utf-8", "replace")
            size = fh.seek(0, io.SEEK_END)
            fh.seek(max(0, size - n))
            tail = fh.read().decode("utf-8", "replace")
    except OSError:
        return "", ""
    return first.strip(), tail


def lock_owner(run_dir: Path) -> tuple[int | None, bool]:
    """``(pid, alive)`` of the process named in ``run.lock`` (``(None, False)`` if none)."""
    owner = read_lock_owner(run_dir)
    if owner is None:
        return None, False
    pid, host = owner
    if host != socket.gethostname():
        return pid, True  # another machine's run: assume it is going on
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return pid, False
    except PermissionError:
        return pid, True
    return pid, True


def run_status(run_dir: Path) -> tuple[str, str, int | None]:
    """``(status, stop_reason, pid)`` of a run folder (see the module docstring)."""
    pid, alive = lock_owner(run_dir)
    if pid is not None:
        return ("running", "", pid) if alive else ("interrupted", "killed", None)
    _, tail = head_tail(run_dir / "log.txt")
    for line in reversed(tail.splitlines()):
        if line.startswith("stopped: "):
            reason = line[9:].split(" at generation")[0]
            return ("interrupted" if reason == "interrupted" else "finished"), reason, None
        if line.startswith("run failed"):
            return "failed", line[:160], None
        if line.startswith(("resumed at", "run ")):
            break
    return "interrupted", "no end logged", None


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
    cells = next(csv.reader([lines[-1]]))
    return dict(zip(cols, cells, strict=False))


def _num(v: Any, default: float = float("nan")) -> float:
    try:
        return float(v)
    except (TypeError, ValueError):
        return default


def study_name(run_dir: Path) -> str:
    """The ``study = "..."`` line of ``config.toml`` (read without parsing the file)."""
    first, _ = head_tail(run_dir / "config.toml", 0)
    if first.startswith("study"):
        return first.partition("=")[2].strip().strip('"')
    return "?"


def summarize(root: Path, run_dir: Path) -> RunSummary:
    status, reason, pid = run_status(run_dir)
    row = last_stats_row(run_dir / "stats.csv")
    return RunSummary(
        name=run_dir.relative_to(root).as_posix(), study=study_name(run_dir), status=status,
        stop_reason=reason, generation=int(_num(row.get("generation"), -1)),
        evaluations=int(_num(row.get("evaluations"), 0)), best=_num(row.get("best_so_far")),
        started=_started(run_dir), duration_s=_num(row.get("wall_s"), 0.0),
        resumable=status == "interrupted" and (run_dir / "checkpoints").is_dir(), pid=pid)


def list_runs(root: Path, study: str | None = None) -> list[RunSummary]:
    root = Path(root)
    runs = [summarize(root, d) for d in find_runs(root)]
    return [r for r in runs if study in (None, "", r.study)]


def resolve_run(root: Path, name: str) -> Path:
    """The run folder ``name`` below ``root``; an :class:`InputError` for anything outside it
    or not a run folder (no path outside RUNS_DIR is ever read)."""
    base = Path(root).resolve()
    path = (base / name).resolve()
    if not path.is_relative_to(base) or path == base or not (path / "config.toml").is_file():
        raise InputError(f"{name}: not a run folder under {root}")
    return path


def safe_file(root: Path, rel: str) -> Path:
    """A file below ``root`` (symbolic links resolved; nothing outside ``root``)."""
    base = Path(root).resolve()
    path = (base / rel).resolve()
    if not path.is_relative_to(base) or not path.is_file():
        raise InputError(f"{rel}: no such file under {root}")
    return path


def read_config(run_dir: Path) -> tuple[str, dict[str, Any]]:
    text = (run_dir / "config.toml").read_text(errors="replace")
    try:
        return text, tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        return text, {}


def log_tail(run_dir: Path, lines: int = 40) -> list[str]:
    _, tail = head_tail(run_dir / "log.txt")
    return tail.splitlines()[-lines:]


class StatsTail:
    """``stats.csv`` read incrementally: :meth:`update` parses only the bytes appended since the
    last call (and starts again when the file was cut back by a resume)."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self.offset = 0
        self.columns: list[str] = []
        self.rows: list[list[float]] = []

    def update(self) -> int:
        """Read what was appended; the number of new rows."""
        try:
            size = self.path.stat().st_size
        except OSError:
            return 0
        if size < self.offset:
            self.offset, self.rows, self.columns = 0, [], []
        if size == self.offset:
            return 0
        with open(self.path, "rb") as fh:
            fh.seek(self.offset)
            chunk = fh.read(size - self.offset)
        end = chunk.rfind(b"\n") + 1  # a half-written last row waits for the next call
        text = chunk[:end].decode("utf-8", "replace")
        self.offset += end
        lines = text.splitlines()
        if not self.columns and lines:
            self.columns = lines.pop(0).split(",")
        new = [[_num(c) for c in cells] for cells in csv.reader(lines)]
        self.rows.extend(new)
        return len(new)

    def column(self, name: str, start: int = 0) -> list[float | None]:
        if name not in self.columns:
            return []
        j = self.columns.index(name)
        return [None if not np.isfinite(r[j]) else r[j] for r in self.rows[start:]
                if len(r) > j]

    def array(self, name: str) -> np.ndarray:
        return np.array([v if v is not None else np.nan for v in self.column(name)], float)


def compare_runs(run_dirs: list[Path], points: int = 200) -> dict[str, list[float]]:
    """Median and interquartile band of the best-so-far fitness of ``run_dirs`` against
    evaluations, on a common grid (a run counts at x once it has made x evaluations and until
    its last row)."""
    curves = []
    for d in run_dirs:
        st = StatsTail(d / "stats.csv")
        st.update()
        e, b = st.array("evaluations"), st.array("best_so_far")
        ok = np.isfinite(e) & np.isfinite(b)
        if ok.any():
            curves.append((e[ok], b[ok]))
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
