"""What a run page lists and tells beside its curves (issue 35): the run's files by kind
(videos played in the page, plots shown, everything downloadable), the tail of its log with
the run's stderr, and its speed and time left.

Files are found by a bounded walk of the run folder (``MAX_FILES`` entries, ``MAX_DEPTH``
levels, symbolic links and the checkpoints left out: they are the run's own, not artifacts);
they are served by the ``/files`` route, which confines every path to the runs folder.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from evomotion.studio.readers import natural_key

MAX_FILES = 500
MAX_DEPTH = 3
SKIPPED = frozenset({"checkpoints", "run.lock", "__pycache__"})
KINDS = (("video", (".mp4", ".webm")), ("image", (".png", ".svg", ".jpg", ".jpeg", ".gif")),
         ("motion", (".motion",)), ("policy", (".onnx", ".npz")),
         ("script", (".py",)), ("data", (".json", ".toml", ".csv", ".rrd", ".bin")),
         ("text", (".txt", ".md", ".log")))
#: the files a run's stderr may be in: the studio's (a run started or resumed from the page)
STDERR_FILES = ("studio-stderr.txt",)


@dataclass(frozen=True)
class RunFile:
    rel: str  # path below the run folder, "/"-separated
    size: int  # bytes
    kind: str  # video | image | motion | policy | script | data | text | other


def kind_of(name: str) -> str:
    low = name.lower()
    for kind, suffixes in KINDS:
        if low.endswith(suffixes):
            return kind
    return "other"


def run_files(run_dir: Path, limit: int = MAX_FILES) -> list[RunFile]:
    """The run's regular files (no links, no checkpoints), at most ``limit``, sorted by kind
    (videos first) and name; unreadable entries are left out."""
    out: list[RunFile] = []

    def walk(folder: Path, prefix: str, depth: int) -> None:
        try:
            with os.scandir(folder) as it:
                entries = sorted(it, key=lambda e: natural_key(e.name))
        except OSError:
            return
        for e in entries:
            if len(out) >= limit:
                return
            if e.name in SKIPPED or e.name.startswith("."):
                continue
            try:
                if e.is_symlink():
                    continue
                if e.is_dir(follow_symlinks=False):
                    if depth < MAX_DEPTH:
                        walk(Path(e.path), prefix + e.name + "/", depth + 1)
                elif e.is_file(follow_symlinks=False):
                    out.append(RunFile(prefix + e.name, e.stat(follow_symlinks=False).st_size,
                                       kind_of(e.name)))
            except OSError:
                continue

    walk(Path(run_dir), "", 1)
    order = [k for k, _ in KINDS] + ["other"]
    return sorted(out, key=lambda f: (order.index(f.kind), natural_key(f.rel)))


def duration_text(seconds: float) -> str:
    """A run's duration for people: 3 significant digits under a minute (0.039 s, 12.3 s;
    it read "0.0 s" for a 0.039 s run), then minutes and seconds, then hours and minutes."""
    s = float(seconds)
    if not s >= 0 or s == float("inf"):
        return ""
    if s < 60:
        return f"{s:.3g} s"
    if s < 3600:
        return f"{int(s // 60)} min {int(s % 60):02d} s"
    return f"{int(s // 3600)} h {int(s % 3600 // 60):02d} min"


def size_text(n: int) -> str:
    for unit, scale in (("GB", 1 << 30), ("MB", 1 << 20), ("kB", 1 << 10)):
        if n >= scale:
            return f"{n / scale:.1f} {unit}"
    return f"{n} B"


def stderr_tail(run_dir: Path, lines: int = 40, max_bytes: int = 16384) -> tuple[str, list[str]]:
    """``(file name, last lines)`` of the run's stderr file, ``("", [])`` when it has none (a
    run started in a terminal printed its stderr there)."""
    from evomotion.studio.readers import head_tail

    for name in STDERR_FILES:
        path = Path(run_dir) / name
        if path.is_file() and not path.is_symlink():
            _, tail = head_tail(path, max_bytes)
            return name, tail.splitlines()[-lines:]
    return "", []


def progress(config: dict[str, Any], generation: float | None, evaluations: float | None,
             wall_s: float | None, rate: float | None, running: bool) -> str:
    """``generation 12 of 100, 1,300 evaluations, 540 evaluations/s, about 1 min 20 s left``:
    the time left from the run's limits (generations, evaluations, wall time) at its mean pace
    so far; only while it runs."""
    run = config.get("run", {}) if isinstance(config.get("run"), dict) else {}
    gens, evals, wall = (_pos(run.get(k)) for k in ("generations", "max_evaluations",
                                                    "wall_seconds"))
    g = None if generation is None else int(generation)
    parts = [f"generation {'-' if g is None else g}" + (f" of {int(gens)}" if gens else "")]
    parts.append(f"{int(evaluations or 0):,} evaluations")
    if rate:
        parts.append(f"{rate:,.0f} evaluations/s" if rate >= 10 else
                     f"{rate:.3g} evaluations/s")
    if running and wall_s and g is not None and g >= 0:
        left = []
        per_gen = wall_s / (g + 1)
        if gens:
            left.append(max(0.0, (gens - g) * per_gen))
        if evals and evaluations and evaluations > 0:
            left.append(max(0.0, (evals - evaluations) * wall_s / evaluations))
        if wall:
            left.append(max(0.0, wall - wall_s))
        if left:
            parts.append(f"about {duration_text(min(left))} left")
    return ", ".join(parts)


def _pos(v: Any) -> float:
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) \
        and math.isfinite(v) and v > 0 else 0.0
