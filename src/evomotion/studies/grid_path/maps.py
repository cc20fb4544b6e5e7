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

The paper's cell numbering (Zhang et al. 2014, sec. 3.1.2) counts cells from 1, starting at
the bottom-left cell, left to right, then row by row upwards: see :func:`cell_number`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from evomotion.errors import FileFormatError, InputError
from evomotion.textio import decode_utf8, read_file_bytes

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
    """Paper's cell number ``P = W * floor(y) + floor(x) + 1`` of points ``(x, y)``."""
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
    """Whether ``b`` is reachable from ``a`` by octile moves.

    A diagonal move needs both side cells free (no corner cutting), so it can always be
    replaced by two straight moves: octile reachability is 4-connectivity of the free cells,
    found with ``scipy.ndimage.label`` (C speed, 4 bytes per cell) instead of a search."""
    from scipy import ndimage

    if tuple(a) == tuple(b):
        return True
    if blocked[b[1], b[0]]:
        return False
    free = ~np.asarray(blocked, dtype=bool)
    free[a[1], a[0]] = True  # the search starts from ``a`` whatever it is
    labels, _ = ndimage.label(free)
    return bool(labels[a[1], a[0]] == labels[b[1], b[0]])


#: Largest map read: 64 Mi cells (e.g. 8,192 x 8,192; 7,100 x 7,100 is 50.4 M). Reading
#: peaks at about 10.5 bytes per cell (file bytes, their lookup, masks, the grid flipped into
#: place, then :func:`connected`'s 4-byte labels): 530 MiB and 0.8 s for 7,100 x 7,100
#: (benchmarks/bench_map_read.py); the map itself keeps 1 byte per cell.
MAX_MAP_CELLS = 64 * 2**20
#: Largest map file: a 0/1 grid with a separator after every cell, plus line ends.
MAX_MAP_BYTES = 3 * MAX_MAP_CELLS + 2**20
#: Largest map the study's exact solvers (``solvers.all_optima``: Python A* with dicts, about
#: 100 bytes and 15 us per expanded cell, then visibility graphs) and its validity-keeping
#: initial population (seconds per path at 1,000 x 1,000) handle in reasonable time and
#: memory: 4 Mi cells (2,048 x 2,048). A 7,100 x 7,100 map reads in about a second, but its
#: A* alone would need about 5 GB; :func:`check_search_size` says so up front.
MAX_SEARCH_CELLS = 4 * 2**20
_FREE, _BLOCK, _SEP, _BAD, _EOL = 0, 1, 2, 3, 4


def check_search_size(m: GridMap, max_cells: int = MAX_SEARCH_CELLS) -> None:
    """Raise :class:`InputError` when ``m`` is larger than the study's searches handle."""
    if m.width * m.height > max_cells:
        raise InputError(f"{m.name}: a {m.width} x {m.height} map has {m.width * m.height:,} "
                         f"cells; the grid-path solvers handle at most {max_cells:,} "
                         "(MAX_SEARCH_CELLS)")


def _lut(free: str, blocked: str, separators: str) -> np.ndarray:
    lut = np.full(256, _BAD, dtype=np.uint8)
    lut[np.frombuffer(free.encode(), np.uint8)] = _FREE
    lut[np.frombuffer(blocked.encode(), np.uint8)] = _BLOCK
    lut[np.frombuffer(separators.encode(), np.uint8)] = _SEP
    lut[ord("\n")] = _EOL
    return lut


_MOVINGAI_LUT = _lut(PASSABLE, BLOCKED, "")
_BINARY_LUT = _lut("0", "1", " ,\t")


def _char_at(body: np.ndarray, k: int) -> str:
    """The character starting at byte ``k`` (the text is valid UTF-8 by then)."""
    return bytes(body[k:k + 4]).decode("utf-8", errors="ignore")[:1] or f"\\x{body[k]:02x}"


def _cells_error(path: Path, line: int, h: int, w: int) -> FileFormatError:
    return FileFormatError(path, line, f"expected a map of at most {MAX_MAP_CELLS:,} cells "
                                       f"(the maximum map size), got {w} x {h} = {h * w:,}")


def _grid(path: Path, body: np.ndarray, first_line: int, lut: np.ndarray, what: str,
          shape: tuple[int, int] | None, map_line: int) -> np.ndarray:
    """``blocked[height, width]`` (row 0 = bottom) from the grid's bytes, vectorised: a lookup
    table from bytes to free / blocked / separator / bad / line end, cells per line by
    ``np.add.reduceat``; blank lines are skipped. ``shape`` = the header's (H, W), if any."""
    n = body.size
    vals = lut[body]
    nl = np.flatnonzero(vals == _EOL)
    cr = nl[(nl > 0)]
    cr = cr[body[cr - 1] == 13] - 1  # '\r' right before '\n' (CRLF) ...
    vals[cr] = _SEP
    if n and body[-1] == 13:  # ... or at the very end
        vals[n - 1] = _SEP
    bad = vals == _BAD
    if bad.any():
        k = int(np.argmax(bad))
        i = int(np.searchsorted(nl, k))
        col = k - (int(nl[i - 1]) + 1 if i else 0) + 1
        raise FileFormatError(path, first_line + i, f"expected only {what}, got "
                                                    f"{_char_at(body, k)!r} at column {col}")
    del bad
    starts = np.concatenate(([0], nl + 1))
    if starts[-1] == n:
        starts = starts[:-1]
    cell = vals < _SEP
    counts = np.add.reduceat(cell, starts, dtype=np.int64) if n else np.zeros(0, np.int64)
    rows = np.flatnonzero(counts > 0)
    lines = first_line + rows
    if shape is None:
        if rows.size == 0:
            raise FileFormatError(path, None, "expected a map, got an empty file")
        h, w = int(rows.size), int(counts[rows[0]])
        if h * w > MAX_MAP_CELLS:
            raise _cells_error(path, int(lines[-1]), h, w)
    else:
        h, w = shape
        if rows.size != h:
            where = int(lines[h]) if rows.size > h else int(lines[-1]) if rows.size else map_line
            raise FileFormatError(path, where, f"expected {h} map rows, got {rows.size}")
    wrong = np.flatnonzero(counts[rows] != w)
    if wrong.size:
        i = int(wrong[0])
        raise FileFormatError(path, int(lines[i]), f"expected a row of {w} cells, "
                                                   f"got {int(counts[rows[i]])}")
    grid = vals[cell]
    del vals, cell
    return np.ascontiguousarray(grid.reshape(h, w)[::-1]).view(bool)  # top row first in files


def read_map(path: str | Path, start: tuple[int, int] | None = None,
             goal: tuple[int, int] | None = None) -> GridMap:
    """Read a Moving AI ``.map`` or a 0/1 text grid; default endpoints are the bottom-left
    and top-right cells. Raises :class:`FileFormatError` / :class:`InputError`.

    The file is read as bytes and decoded with numpy in time and memory proportional to its
    size; its size (:data:`MAX_MAP_BYTES`) and the header's cell count
    (:data:`MAX_MAP_CELLS`) are checked before anything big is allocated."""
    path = Path(path)
    data = read_file_bytes(path, "map file", MAX_MAP_BYTES)
    arr = np.frombuffer(data, dtype=np.uint8)
    if arr.size and int(arr.max()) >= 0x80:
        decode_utf8(data, path)  # bad UTF-8 is reported as such; valid UTF-8 is a bad cell
    lead = len(data) - len(data.lstrip())
    if lead == len(data):
        raise FileFormatError(path, None, "expected a map, got an empty file")
    if data[lead:lead + 5].rstrip() == b"type":
        blocked = _read_movingai(path, data, arr)
    else:
        blocked = _grid(path, arr, 1, _BINARY_LUT, "'0' and '1'", None, 1)
    h, w = blocked.shape
    m = GridMap(blocked, (0, 0), (w - 1, h - 1), path.name)
    return m.with_endpoints(start, goal)


_HEADER = "expected 'type T', 'height H', 'width W' or 'map'"


def _read_movingai(path: Path, data: bytes, arr: np.ndarray) -> np.ndarray:
    """The header (``type octile``, ``height H``, ``width W``, ``map``; H, W >= 1) line by
    line, then the grid vectorised."""
    head: dict[str, tuple[int, str]] = {}
    pos, lineno, last = 0, 0, 1
    while True:
        if pos >= len(data):
            raise FileFormatError(path, last, "expected a 'map' line after the header")
        end = data.find(b"\n", pos)
        end = len(data) if end < 0 else end
        raw, pos, lineno = data[pos:min(end, pos + 201)], end + 1, lineno + 1
        parts = raw.decode("utf-8", errors="replace").split()
        if not parts:
            continue
        last = lineno
        if parts == ["map"]:
            break
        if len(raw) > 200 or len(parts) != 2 or parts[0] not in ("type", "height", "width"):
            raise FileFormatError(path, lineno, _HEADER)
        key, value = parts
        if key in head:
            raise FileFormatError(path, lineno, f"expected '{key}' once in the header "
                                                f"(first on line {head[key][0]})")
        head[key] = (lineno, value)
        if key == "type" and value != "octile":
            raise FileFormatError(path, lineno, f"expected 'type octile', got 'type "
                                                f"{value[:20]}'")
        if key in ("height", "width") and not (value.isascii() and value.isdigit()
                                               and len(value) <= 9 and int(value) >= 1):
            raise FileFormatError(path, lineno, f"expected '{key} N' with an integer N >= 1, "
                                                f"got '{key} {value[:20]}'")
    for key in ("type", "height", "width"):
        if key not in head:
            raise FileFormatError(path, lineno, f"expected a '{key}' line before 'map'")
    h, w = int(head["height"][1]), int(head["width"][1])
    if h * w > MAX_MAP_CELLS:
        raise _cells_error(path, max(head["height"][0], head["width"][0]), h, w)
    return _grid(path, arr[pos:], lineno + 1, _MOVINGAI_LUT,
                 "'.GS' (free) and '@OTW' (blocked)", (h, w), lineno)


def write_map(path: str | Path, blocked: np.ndarray) -> None:
    """Write ``blocked`` (row 0 = bottom) as a Moving AI ``.map`` file (atomically; the
    folder must exist)."""
    from evomotion.outfile import atomic_write_text

    h, w = blocked.shape
    rows = ["".join("@" if b else "." for b in row) for row in blocked[::-1]]
    atomic_write_text(path, f"type octile\nheight {h}\nwidth {w}\nmap\n" + "\n".join(rows)
                      + "\n", "map file")


#: cells drawn and labelled by :func:`random_map` in all its tries at most (a few seconds):
#: a large map gets fewer tries than ``max_tries``
RANDOM_MAP_WORK = 2**24


def random_map(size: int, density: float, rng: np.random.Generator,
               max_tries: int = 1000) -> GridMap:
    """A ``size`` x ``size`` map with ``round(density * cells)`` obstacles placed uniformly,
    start bottom-left and goal top-right free and connected (re-drawn until they are, at
    most ``max_tries`` times and :data:`RANDOM_MAP_WORK` cells in all)."""
    if size < 2 or not 0.0 <= density < 1.0:
        raise InputError(f"random map needs size >= 2 and 0 <= density < 1, got {size}, "
                         f"{density}")
    n = size * size
    k = int(round(density * n))
    max_tries = min(max_tries, max(2, RANDOM_MAP_WORK // n))
    for _ in range(max_tries):
        flat = np.zeros(n, dtype=bool)
        others = np.arange(1, n - 1)
        flat[rng.choice(others, size=min(k, n - 2), replace=False)] = True
        blocked = flat.reshape(size, size)
        if connected(blocked, (0, 0), (size - 1, size - 1)):
            return GridMap(blocked, (0, 0), (size - 1, size - 1), f"random-{size}")
    raise InputError(f"no connected {size}x{size} map at density {density} in {max_tries} tries")
