"""Grid maps: Moving AI ``.map`` and plain 0/1 readers, a writer and a random map maker.

Conventions (cell units): the map is ``width`` x ``height`` unit squares; the origin is the
bottom-left corner, x to the right, y up. ``blocked[y, x]`` is True for an obstacle, with
``y = 0`` the *bottom* row (files list the top row first, as Moving AI does). A cell is
named by ``(x, y)`` integer indices; its centre is ``(x + 0.5, y + 0.5)``.

Moving AI format (Sturtevant 2012, movingai.com/benchmarks/formats.html)::

    type octile
    height H
    width W
    map
    <H rows of W characters>    '.', 'G', 'S' passable; '@', 'O', 'T', 'W' blocked

The seed's cell numbering (Zhang et al. 2014, sec. 3.1.2) counts cells from 1, starting at
the bottom-left cell, left to right, then row by row upwards: see :func:`cell_number`.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from evomotion.errors import FileFormatError, InputError

PASSABLE, BLOCKED = ".GS", "@OTW"


@dataclass(frozen=True)
class GridMap:
    """An obstacle grid with a start and a goal cell (``(x, y)`` indices)."""

    blocked: np.ndarray  # bool[height, width], row 0 = bottom
    start: tuple[int, int]
    goal: tuple[int, int]
    name: str = "map"

    @property
    def height(self) -> int:
        return int(self.blocked.shape[0])

    @property
    def width(self) -> int:
        return int(self.blocked.shape[1])

    @property
    def start_xy(self) -> np.ndarray:
        return np.array(self.start, dtype=float) + 0.5

    @property
    def goal_xy(self) -> np.ndarray:
        return np.array(self.goal, dtype=float) + 0.5

    def with_endpoints(self, start: tuple[int, int] | None, goal: tuple[int, int] | None,
                       ) -> GridMap:
        s = self.start if start is None else tuple(int(v) for v in start)
        g = self.goal if goal is None else tuple(int(v) for v in goal)
        m = GridMap(self.blocked, s, g, self.name)  # type: ignore[arg-type]
        m.check()
        return m

    def check(self) -> None:
        """Raise :class:`InputError` for an off-map or blocked endpoint or no connection."""
        for what, (x, y) in (("start", self.start), ("goal", self.goal)):
            if not (0 <= x < self.width and 0 <= y < self.height):
                raise InputError(f"{self.name}: {what} cell ({x}, {y}) is outside the "
                                 f"{self.width}x{self.height} map")
            if self.blocked[y, x]:
                raise InputError(f"{self.name}: {what} cell ({x}, {y}) is blocked")
        if not connected(self.blocked, self.start, self.goal):
            raise InputError(f"{self.name}: the start {self.start} is cut off from the goal "
                             f"{self.goal} (no 8-connected path without corner cutting)")


def cell_number(x: np.ndarray, y: np.ndarray, width: int) -> np.ndarray:
    """Seed's cell number ``P = W * floor(y) + floor(x) + 1`` of points ``(x, y)``."""
    return width * np.floor(y).astype(int) + np.floor(x).astype(int) + 1


def cell_centre(P: np.ndarray, width: int) -> tuple[np.ndarray, np.ndarray]:
    """Centre ``(x, y)`` of the cell numbered ``P`` (inverse of :func:`cell_number`)."""
    q = np.asarray(P) - 1
    return q % width + 0.5, q // width + 0.5


def octile_moves(blocked: np.ndarray, x: int, y: int) -> list[tuple[int, int, bool]]:
    """Free 8-neighbours ``(x', y', diagonal)``; diagonals need both side cells free."""
    h, w = blocked.shape
    out = []
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            if (dx or dy) and 0 <= x + dx < w and 0 <= y + dy < h and not blocked[y + dy, x + dx]:
                if dx and dy and (blocked[y, x + dx] or blocked[y + dy, x]):
                    continue
                out.append((x + dx, y + dy, bool(dx and dy)))
    return out


def connected(blocked: np.ndarray, a: tuple[int, int], b: tuple[int, int]) -> bool:
    """Whether ``b`` is reachable from ``a`` by octile moves (breadth-first search)."""
    seen = np.zeros_like(blocked, dtype=bool)
    seen[a[1], a[0]] = True
    todo = deque([a])
    while todo:
        x, y = todo.popleft()
        if (x, y) == tuple(b):
            return True
        for nx, ny, _ in octile_moves(blocked, x, y):
            if not seen[ny, nx]:
                seen[ny, nx] = True
                todo.append((nx, ny))
    return False


def _grid_from_rows(path: Path, rows: list[tuple[int, str]], alphabet: dict[str, bool],
                    what: str) -> np.ndarray:
    width = len(rows[0][1])
    grid = np.zeros((len(rows), width), dtype=bool)
    for i, (lineno, text) in enumerate(rows):
        if len(text) != width:
            raise FileFormatError(path, lineno, f"expected a row of {width} cells, "
                                                f"got {len(text)}")
        for j, ch in enumerate(text):
            if ch not in alphabet:
                raise FileFormatError(path, lineno, f"expected only {what}, got {ch!r} at "
                                                    f"column {j + 1}")
            grid[i, j] = alphabet[ch]
    return grid[::-1].copy()  # files list the top row first


def read_map(path: str | Path, start: tuple[int, int] | None = None,
             goal: tuple[int, int] | None = None) -> GridMap:
    """Read a Moving AI ``.map`` or a 0/1 text grid; default endpoints are the bottom-left
    and top-right cells. Raises :class:`FileFormatError` / :class:`InputError`."""
    path = Path(path)
    try:
        lines = path.read_text().splitlines()
    except OSError as e:
        raise InputError(f"{path}: cannot read map ({e.strerror})") from None
    numbered = [(i + 1, ln.strip()) for i, ln in enumerate(lines) if ln.strip()]
    if not numbered:
        raise FileFormatError(path, None, "expected a map, got an empty file")
    if numbered[0][1].split()[0] == "type":
        blocked = _read_movingai(path, numbered)
    else:
        rows = [(n, t.replace(" ", "").replace(",", "")) for n, t in numbered]
        blocked = _grid_from_rows(path, rows, {"0": False, "1": True}, "'0' and '1'")
    h, w = blocked.shape
    m = GridMap(blocked, (0, 0), (w - 1, h - 1), path.name)
    return m.with_endpoints(start, goal)


def _read_movingai(path: Path, numbered: list[tuple[int, str]]) -> np.ndarray:
    head: dict[str, str] = {}
    for k, (lineno, text) in enumerate(numbered):
        if text == "map":
            body = numbered[k + 1:]
            break
        parts = text.split()
        if len(parts) != 2 or parts[0] not in ("type", "height", "width"):
            raise FileFormatError(path, lineno, "expected 'type T', 'height H', 'width W' "
                                                "or 'map'")
        head[parts[0]] = parts[1]
    else:
        raise FileFormatError(path, numbered[-1][0], "expected a 'map' line after the header")
    try:
        h, w = int(head["height"]), int(head["width"])
    except (KeyError, ValueError):
        raise FileFormatError(path, numbered[0][0], "expected integer 'height' and 'width' "
                                                    "in the header") from None
    if len(body) != h:
        where = body[-1][0] if body else numbered[-1][0]
        raise FileFormatError(path, where, f"expected {h} map rows, got {len(body)}")
    alphabet = {c: False for c in PASSABLE} | {c: True for c in BLOCKED}
    grid = _grid_from_rows(path, body, alphabet, "'.GS' (free) and '@OTW' (blocked)")
    if grid.shape[1] != w:
        raise FileFormatError(path, body[0][0], f"expected rows of width {w}, "
                                                f"got {grid.shape[1]}")
    return grid


def write_map(path: str | Path, blocked: np.ndarray) -> None:
    """Write ``blocked`` (row 0 = bottom) as a Moving AI ``.map`` file."""
    h, w = blocked.shape
    rows = ["".join("@" if b else "." for b in row) for row in blocked[::-1]]
    Path(path).write_text(f"type octile\nheight {h}\nwidth {w}\nmap\n" + "\n".join(rows) + "\n")


def random_map(size: int, density: float, rng: np.random.Generator,
               max_tries: int = 1000) -> GridMap:
    """A ``size`` x ``size`` map with ``round(density * cells)`` obstacles placed uniformly,
    start bottom-left and goal top-right free and connected (re-drawn until they are)."""
    if size < 2 or not 0.0 <= density < 1.0:
        raise InputError(f"random map needs size >= 2 and 0 <= density < 1, got {size}, "
                         f"{density}")
    n = size * size
    k = int(round(density * n))
    for _ in range(max_tries):
        flat = np.zeros(n, dtype=bool)
        others = np.arange(1, n - 1)
        flat[rng.choice(others, size=min(k, n - 2), replace=False)] = True
        blocked = flat.reshape(size, size)
        if connected(blocked, (0, 0), (size - 1, size - 1)):
            return GridMap(blocked, (0, 0), (size - 1, size - 1), f"random-{size}")
    raise InputError(f"no connected {size}x{size} map at density {density} in {max_tries} tries")
