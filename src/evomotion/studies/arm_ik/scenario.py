"""Scenario files of paper 001 (Januszkiewicz & Kowalski 2011, section 1.1).

One value group per line; lines starting with ``#`` are comments and blank lines are
skipped. In order: board width, board height, start point ``X Y``, the number of targets
(= number of fingers), the targets, the number of arm bones, one ``length min_deg max_deg``
line per arm bone, then for every finger its bone count and bone lines, then the number of
obstacles and for each obstacle its point count and points. An obstacle is the polyline
through its points; it is closed when the last point repeats the first.

Angles (degrees) are counter-clockwise rotations relative to the previous bone, 0 meaning
straight on; the first arm bone is relative to +x, the first bone of every finger relative
to the last arm bone. Limits satisfy ``0 <= min <= max <= 360``.

Numbers are plain decimal numbers (no ``nan``/``inf``, no ``_``), of magnitude at most
:data:`MAX_ABS`; counts are ASCII integers up to the maxima in :data:`MAX_COUNTS`; the file is
UTF-8 of at most :data:`MAX_SCENARIO_BYTES`. Every violation is a
:class:`~evomotion.errors.FileFormatError` naming the file and line.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from evomotion.errors import FileFormatError
from evomotion.textio import decode_utf8, read_file_bytes, split_lines

SCENARIO_DIR = Path(__file__).parent / "scenarios"
MAX_SCENARIO_BYTES = 16 * 1024 * 1024
MAX_ABS = 1e6  # [board units]: the largest coordinate, size or bone length read
#: The largest counts read (the genome has one gene per bone; obstacles are tested per edge).
MAX_COUNTS = {"targets": 64, "bones": 64, "obstacles": 10_000, "points": 100_000}
_NUMBER = re.compile(r"^[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?$")
_INTEGER = re.compile(r"^\+?[0-9]{1,9}$|^-[0-9]{1,9}$")


@dataclass(frozen=True)
class Chain:
    """A chain of bones: ``length[k]`` (board units) and joint limits ``min_deg/max_deg[k]``."""

    length: np.ndarray
    min_deg: np.ndarray
    max_deg: np.ndarray

    @property
    def n_bones(self) -> int:
        return int(self.length.size)

    def reach(self) -> tuple[float, float]:
        """Conservative [min, max] distance from the chain's base to its tip.

        ``max = sum(length)``; ``min = max(0, longest - rest)`` (triangle inequality). Both hold
        for any joint limits, so no reachable position is ever excluded.
        """
        total = float(self.length.sum())
        longest = float(self.length.max())
        return max(0.0, 2 * longest - total), total


@dataclass(frozen=True)
class Scenario:
    """A parsed scenario; points are ``[x, y]`` in board units."""

    name: str
    width: float
    height: float
    start: np.ndarray  # (2,)
    targets: np.ndarray  # (T, 2)
    arm: Chain
    fingers: tuple[Chain, ...]
    obstacles: tuple[np.ndarray, ...]  # each (k, 2), k >= 2

    @property
    def diagonal(self) -> float:
        return math.hypot(self.width, self.height)

    @property
    def n_targets(self) -> int:
        return int(self.targets.shape[0])

    def obstacle_segments(self) -> np.ndarray:
        """All obstacle edges as ``(M, 2, 2)`` = (segment, endpoint, xy)."""
        segs = [np.stack([p[:-1], p[1:]], axis=1) for p in self.obstacles]
        return np.concatenate(segs) if segs else np.zeros((0, 2, 2))

    def summary(self) -> str:
        lo, hi = self.arm.reach()
        lines = [
            f"scenario {self.name}: board {self.width:g} x {self.height:g}, "
            f"start ({self.start[0]:g}, {self.start[1]:g})",
            f"  {self.n_targets} targets / fingers: "
            + ", ".join(f"({x:g}, {y:g})" for x, y in self.targets),
            f"  arm: {self.arm.n_bones} bones, reach [{lo:g}, {hi:g}]",
        ]
        for j, f in enumerate(self.fingers):
            flo, fhi = f.reach()
            lines.append(f"  finger {j + 1}: {f.n_bones} bones, reach [{flo:g}, {fhi:g}]")
        closed = sum(bool(np.array_equal(p[0], p[-1])) for p in self.obstacles)
        lines.append(
            f"  {len(self.obstacles)} obstacles ({closed} closed), "
            f"{self.obstacle_segments().shape[0]} edges"
        )
        return "\n".join(lines)


class _Lines:
    """Cursor over the non-comment lines of a file, raising FileFormatError on bad values."""

    def __init__(self, text: str, path: str) -> None:
        self.path = path
        self.rows: list[tuple[int, list[str]]] = []
        last = 0
        for no, raw in enumerate(split_lines(text), start=1):
            last = no
            s = raw.strip()
            if s and not s.startswith("#"):
                self.rows.append((no, s.split()))
        self.eof_line = last + 1
        self.i = 0

    def _next(self, what: str) -> tuple[int, list[str]]:
        if self.i >= len(self.rows):
            raise FileFormatError(self.path, self.eof_line, f"expected {what}, got end of file")
        row = self.rows[self.i]
        self.i += 1
        return row

    def numbers(self, what: str, n: int) -> tuple[int, list[float]]:
        no, toks = self._next(what)
        if len(toks) != n:
            raise FileFormatError(
                self.path, no, f"expected {what} ({n} values), got {len(toks)} values"
            )
        vals = []
        for t in toks:
            if not _NUMBER.match(t):
                raise FileFormatError(
                    self.path, no, f"expected {what}, got non-numeric {_short(t)!r}")
            v = float(t)
            if not (math.isfinite(v) and abs(v) <= MAX_ABS):
                raise FileFormatError(self.path, no, f"expected {what} as finite numbers of "
                                                     f"magnitude <= {MAX_ABS:g}, got {_short(t)!r}")
            vals.append(v)
        return no, vals

    def count(self, what: str, minimum: int, kind: str) -> int:
        no, toks = self._next(what)
        if len(toks) != 1 or not _INTEGER.match(toks[0]):
            got = _short(" ".join(toks))
            raise FileFormatError(self.path, no, f"expected {what} (one integer), got {got!r}")
        v = int(toks[0])
        if v < minimum:
            raise FileFormatError(self.path, no, f"expected {what} >= {minimum}, got {v}")
        if v > MAX_COUNTS[kind]:
            raise FileFormatError(self.path, no, f"expected {what} <= {MAX_COUNTS[kind]} "
                                                 f"(the maximum), got {v}")
        return v

    def positive(self, what: str) -> float:
        no, (v,) = self.numbers(what, 1)
        if v <= 0:
            raise FileFormatError(self.path, no, f"expected {what} > 0, got {v:g}")
        return v

    def point(self, what: str, width: float, height: float, inside: bool) -> np.ndarray:
        no, (x, y) = self.numbers(what, 2)
        if inside and not (0 <= x <= width and 0 <= y <= height):
            raise FileFormatError(
                self.path, no, f"expected {what} inside the board [0, {width:g}] x [0, {height:g}]"
                f", got ({x:g}, {y:g})"
            )
        return np.array([x, y])

    def chain(self, what: str) -> Chain:
        k = self.count(f"number of bones of the {what}", 1, "bones")
        rows = []
        for b in range(k):
            label = f"{what} bone {b + 1} 'length min_deg max_deg'"
            no, (length, lo, hi) = self.numbers(label, 3)
            if length <= 0:
                raise FileFormatError(self.path, no,
                                      f"expected {label} with length > 0, got {length:g}")
            if not 0 <= lo <= hi <= 360:
                raise FileFormatError(
                    self.path, no,
                    f"expected {label} with 0 <= min <= max <= 360, got {lo:g} {hi:g}",
                )
            rows.append((length, lo, hi))
        a = np.array(rows, dtype=float)
        return Chain(a[:, 0].copy(), a[:, 1].copy(), a[:, 2].copy())


def parse_scenario_text(text: str, path: str = "<text>", name: str | None = None) -> Scenario:
    """Parse scenario ``text``; errors name ``path``, the line and what was expected."""
    c = _Lines(text, path)
    width = c.positive("board width")
    height = c.positive("board height")
    start = c.point("start point 'X Y'", width, height, inside=True)
    n_targets = c.count("number of targets", 1, "targets")
    targets = np.stack(
        [c.point(f"target {t + 1} 'X Y'", width, height, inside=True) for t in range(n_targets)]
    )
    arm = c.chain("arm")
    fingers = tuple(c.chain(f"finger {j + 1}") for j in range(n_targets))
    n_obst = c.count("number of obstacles", 0, "obstacles")
    obstacles = []
    for o in range(n_obst):
        k = c.count(f"number of points of obstacle {o + 1}", 2, "points")
        pts = [c.point(f"obstacle {o + 1} point {p + 1} 'X Y'", width, height, False)
               for p in range(k)]
        obstacles.append(np.stack(pts))
    if c.i < len(c.rows):
        no, toks = c.rows[c.i]
        raise FileFormatError(path, no,
                              f"expected end of file, got extra line {_short(' '.join(toks))!r}")
    return Scenario(name or Path(path).stem, width, height, start, targets, arm, fingers,
                    tuple(obstacles))


#: Old names of bundled scenarios, still accepted (run folders and commands from before
#: issue 32): ``seed_example`` is the old name of ``paper_example``.
OLD_SCENARIO_NAMES = {"seed_example": "paper_example"}


def load_scenario(name_or_path: str | Path) -> Scenario:
    """A bundled scenario by name (``paper_example``; old names in
    :data:`OLD_SCENARIO_NAMES`) or a scenario file by path."""
    p = Path(name_or_path)
    try:
        exists = p.exists()
    except (OSError, ValueError):  # e.g. a NUL in the name
        exists = False
    if not exists:  # a bundled name (an old one read as its new name)
        name_or_path = OLD_SCENARIO_NAMES.get(str(name_or_path), name_or_path)
        bundled = SCENARIO_DIR / f"{name_or_path}.scen"
        if bundled.is_file():
            p = bundled
        else:
            avail = ", ".join(bundled_names())
            raise FileFormatError(name_or_path, None,
                                  f"expected a scenario file or a bundled name ({avail})")
    text = decode_utf8(read_file_bytes(p, "scenario file", MAX_SCENARIO_BYTES), p)
    return parse_scenario_text(text, str(p))


def _short(text: str, n: int = 40) -> str:
    return text if len(text) <= n else text[:n] + "..."


def bundled_names() -> list[str]:
    return sorted(q.stem for q in SCENARIO_DIR.glob("*.scen"))
