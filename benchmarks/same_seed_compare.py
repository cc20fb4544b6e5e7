"""What ``same_seed.py`` compares: a case folder reduced to its deterministic content, and the
first difference between two such reductions.

Kept, per file (relative path -> value):

- ``.json``: the parsed document without timing keys (:data:`TIMING_KEY`: wall/CPU/elapsed
  times, ``*_per_s`` rates, ``*_ms`` planning times, ``seconds``, and the byte offsets of a
  checkpoint into ``stats.csv`` / ``log.txt``, whose lengths follow the timing columns);
- ``.csv``: header and cells (as written: floats bit for bit) without timing columns;
- ``.npz``: every array's dtype, shape and SHA-256 of its bytes;
- ``.toml``: the parsed document (``config.toml``: a renamed key shows);
- captured stdout: as a ``.json`` file when it is a JSON document (``--json``), else as text;
- ``.md``, ``.motion``, ``.py``, ``.txt``: the lines, with markdown and
  fixed-width table columns of times blanked and ``<number> s`` / ``<number> ms`` masked in
  prose;
- anything else (``population.bin``, ...): SHA-256 of the bytes.

Skipped: pictures and videos (``.png``, ``.svg``, ``.gif``, ``.mp4``, ``.pdf``: renderer
metadata), ``log.txt`` (times in prose), ``run.lock`` and the ``.evomotion-run`` marker
(bookkeeping). Absolute paths are replaced by ``<case>`` (the case folder) and ``<src>/…/NAME``
(a file of the tree under test, wherever the tree keeps it); ``--rename OLD=NEW`` reads a
renamed name (a scenario, a preset) in the baseline's outputs as the new one.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import re
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

SKIP_SUFFIXES = {".png", ".svg", ".gif", ".mp4", ".pdf"}
SKIP_NAMES = {"run.lock", "log.txt", ".evomotion-run"}
TEXT_SUFFIXES = {".md", ".motion", ".py", ".txt", ".map", ".out"}
TIMING_KEY = re.compile(r"(^|[_.])(wall|cpu|elapsed)(_|$)|per_s$|(^|[_.])ms(_|$)|"
                        r"(^|[_.])seconds$|_seconds$|_offset$")
TABLE_TIMING_HEADER = re.compile(r"\b(wall|cpu|ms)\b|s/run|exp/s|^time s$|seconds",
                                 re.IGNORECASE)
FIXED_WIDTH_TIMING = ("time s", "ms med", "ms max", "exp/s", "1-shot ms")
PROSE_TIME = re.compile(r"\b\d+(\.\d+)?(e[-+]?\d+)? ?m?s\b")
MD_RULE = re.compile(r"^\|(\s*:?-+:?\s*\|)+\s*$")


class Paths:
    """Replaces the absolute paths of one side by names both sides share, and (``renames``,
    given to the baseline's side) an old name by its new one."""

    def __init__(self, case_dir: Path, src: Path, renames: dict[str, str] | None = None) -> None:
        self.case, self.src = str(case_dir), str(src)
        self.in_src = re.compile(re.escape("<src>") + r"/[^\s\"',]*/([^/\s\"',]+)")
        self.renames = [(re.compile(rf"(?<![\w-]){re.escape(o)}(?![\w-])"), n)
                        for o, n in (renames or {}).items()]

    def __call__(self, text: str) -> str:
        text = text.replace(self.case, "<case>").replace(self.src, "<src>")
        for old, new in self.renames:
            text = old.sub(new, text)
        return self.in_src.sub(r"<src>/…/\1", text)


def _json_clean(obj: Any, paths: Paths) -> Any:
    if isinstance(obj, dict):
        return {paths(str(k)): _json_clean(v, paths) for k, v in obj.items()
                if not TIMING_KEY.search(str(k))}
    if isinstance(obj, list):
        return [_json_clean(v, paths) for v in obj]
    if isinstance(obj, str):
        return paths(obj)
    if isinstance(obj, float) and obj != obj:
        return "NaN"  # NaN == NaN here
    return obj


def _csv(text: str) -> dict:
    rows = list(csv.reader(io.StringIO(text)))
    if not rows:
        return {"columns": [], "rows": []}
    keep = [i for i, h in enumerate(rows[0]) if not TIMING_KEY.search(h)]
    return {"columns": [rows[0][i] for i in keep],
            "rows": [[r[i] if i < len(r) else None for i in keep] for r in rows[1:]]}


def _md_tables(lines: list[str]) -> list[str]:
    """Blank the cells of markdown table columns whose header is a time."""
    out, drop = [], set()
    for i, line in enumerate(lines):
        if line.startswith("|"):
            cells = line.strip().strip("|").split("|")
            if i + 1 < len(lines) and MD_RULE.match(lines[i + 1]) and not MD_RULE.match(line):
                drop = {j for j, c in enumerate(cells) if TABLE_TIMING_HEADER.search(c.strip())}
            out.append("|" + "|".join("…" if j in drop else c for j, c in enumerate(cells)) + "|")
        else:
            drop = set()
            out.append(line)
    return out


def _fixed_width_tables(lines: list[str]) -> list[str]:
    """Blank the columns of a whitespace-aligned table (``quadruped-plan study``) headed by a
    time, from its header to the next empty line."""
    out, spans = [], []
    for line in lines:
        if not line.strip():
            spans = []
        heads = [h for h in FIXED_WIDTH_TIMING if h in line and not line.startswith("|")]
        if heads:
            spans = []
            for h in heads:
                end = line.index(h) + len(h)
                start = len(line[:line.index(h)].rstrip())
                spans.append((start, end))
        for start, end in spans:
            line = line[:start] + " " * max(0, min(end, len(line)) - start) + line[end:]
        out.append(line)
    return out


def stdout_value(text: str, paths: Paths) -> Any:
    """A command's stdout: a JSON document (``--json``) as a ``.json`` file, else its lines."""
    if text.lstrip().startswith(("{", "[")):
        try:
            return _json_clean(json.loads(text), paths)
        except ValueError:
            pass
    return text_lines(text, paths)


def text_lines(text: str, paths: Paths) -> list[str]:
    lines = _fixed_width_tables(_md_tables(paths(text).splitlines()))
    return [PROSE_TIME.sub("<t>", ln) if not ln.startswith("|") else ln for ln in lines]


def _npz(data: bytes) -> dict:
    with np.load(io.BytesIO(data), allow_pickle=False) as z:
        return {k: {"dtype": str(z[k].dtype), "shape": list(z[k].shape),
                    "sha256": hashlib.sha256(np.ascontiguousarray(z[k]).tobytes()).hexdigest()}
                for k in sorted(z.files)}


def file_value(path: Path, paths: Paths) -> Any:
    """The deterministic content of one file (see the module docstring)."""
    data = path.read_bytes()
    suffix = path.suffix.lower()
    try:
        if suffix == ".json":
            return _json_clean(json.loads(data), paths)
        if suffix == ".csv":
            return _csv(paths(data.decode()))
        if suffix == ".npz":
            return _npz(data)
        if suffix == ".toml":
            return _json_clean(tomllib.loads(data.decode()), paths)
        if suffix in TEXT_SUFFIXES:
            return text_lines(data.decode(), paths)
    except (ValueError, UnicodeDecodeError, OSError) as e:
        return {"unreadable": f"{type(e).__name__}: {e}",
                "sha256": hashlib.sha256(data).hexdigest()}
    return {"sha256": hashlib.sha256(data).hexdigest(), "bytes": len(data)}


def folder_values(folder: Path, paths: Paths) -> dict[str, Any]:
    """Every compared file under ``folder`` (relative path -> value)."""
    out = {}
    for p in sorted(folder.rglob("*")):
        if p.is_dir() or p.is_symlink() or p.name in SKIP_NAMES \
                or p.suffix.lower() in SKIP_SUFFIXES:
            continue
        out[p.relative_to(folder).as_posix()] = file_value(p, paths)
    return out


def _short(v: Any) -> str:
    s = json.dumps(v, default=str, ensure_ascii=False)
    return s if len(s) <= 60 else s[:57] + "..."


def _where(path: list) -> str:
    if not path:
        return "(top)"
    rest = "".join(f"[{k}]" if isinstance(k, int) else f".{k}" for k in path[1:])
    return f"{path[0]} {rest.lstrip('.')}".rstrip()


def first_difference(old: Any, new: Any, path: list | None = None) -> str | None:
    """Where ``old`` and ``new`` first differ (file, key path) and the two values there; None
    if they are equal."""
    path = path or []
    if isinstance(old, dict) and isinstance(new, dict):
        for k in list(old) + [k for k in new if k not in old]:
            if k not in new:
                return f"{_where(path + [k])}: only in the baseline"
            if k not in old:
                return f"{_where(path + [k])}: only in this tree"
            d = first_difference(old[k], new[k], path + [k])
            if d:
                return d
        return None
    if isinstance(old, list) and isinstance(new, list):
        for i, (a, b) in enumerate(zip(old, new)):
            d = first_difference(a, b, path + [i])
            if d:
                return d
        if len(old) != len(new):
            return f"{_where(path)}: {len(old)} items -> {len(new)}"
        return None
    if type(old) is not type(new) or old != new:
        return f"{_where(path)}: {_short(old)} -> {_short(new)}"
    return None
