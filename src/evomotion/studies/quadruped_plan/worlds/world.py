"""World files for quadruped plans: bounds, start, goal, no-step zones and obstacles.

A world is a UTF-8 text file, one statement per line, lengths in the paper's units, angles in
degrees; ``#`` starts a comment::

    name corridor                      # optional label
    bounds -6 -6 40 30                 # xmin ymin xmax ymax: the body and feet stay inside
    start 0 0 270                      # body centre x y, body X-axis angle phi [deg]
    goal 30 20 0.25                    # x y [tolerance, default 0.25]
    view 8                             # how far the robot sees hidden obstacles (default 8)
    nostep 4 -3  6 -3  6 3  4 3        # a polygon no foot may be placed in (>= 3 vertices)
    obstacle 10 5  12 5  12 30  10 30  # a polygon the body and legs may not cross
    hidden 20 8  21 8  21 9  20 9      # an obstacle unknown until within ``view``

Polygons are simple (edges do not cross), in either orientation. Every error names the file,
the line and what was expected (:class:`evomotion.errors.FileFormatError`). Bundled worlds
(``corridor``, ``gaps``, ``field``) are found by name (:func:`load_world`); every world,
bundled or named by a path (in a configuration, a plan's check, the missions table), is read
by :func:`read_world`, which refuses a FIFO, a device or a folder without blocking.

Physical range, checked before anything is allocated: coordinates finite and at most
``MAX_ABS`` (10,000 units = 1 km at 0.1 m per unit) in magnitude; the bounds (given, or the
points named plus 6 units) span at most ``MAX_GRID_NODES`` nodes of the planner's
``PLAN_GRID`` (0.1-unit) distance grids, e.g. 140 x 140 units; at most ``MAX_POLYGONS``
polygons of 3 to ``MAX_VERTICES`` vertices, ``MAX_TOTAL_VERTICES`` in all, and the
polygon-distance work of building the grids (grid nodes near a polygon times its vertices,
summed) at most ``MAX_CARVE_WORK``. The start and the goal lie outside every obstacle and
no-step zone (whether the robot can stand there is the planner's test, see
:func:`evomotion.studies.quadruped_plan.worlds.terrain.stand_problem`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from evomotion.errors import FileFormatError, InputError
from evomotion.studies.quadruped_plan.worlds.geometry import inside, simple_polygon_problem
from evomotion.textio import read_text_lines

WORLD_DIR = Path(__file__).parent  # the bundled *.world files lie beside this module
MAX_WORLD_BYTES = 1 << 20
MAX_ABS = 1e4  # [units]
MAX_VERTICES = 1000
MAX_POLYGONS = 500
MAX_TOTAL_VERTICES = 20_000
PLAN_GRID = 0.1  # [units] node spacing of the planner's distance grids (terrain.py)
GRID_REACH = 7.0  # [units] distances are carved this far round a polygon (terrain.CAP)
MAX_GRID_NODES = 2_000_000  # per grid: two grids of floats and their row lists < 400 MB
MAX_CARVE_WORK = 40_000_000  # node x vertex distance evaluations to build the grids (~2 s)
KEYWORDS = ("name", "bounds", "start", "goal", "view", "nostep", "obstacle", "hidden")


@dataclass(frozen=True)
class Polygon:
    kind: str  # "nostep", "obstacle" or "hidden"
    points: np.ndarray  # (n, 2)
    line: int = 0  # line in the world file (0: made in code)

    def to_json(self) -> dict:
        return {"kind": self.kind, "points": self.points.tolist()}


@dataclass(frozen=True)
class World:
    """A parsed world; ``polygons`` keep the file's order."""

    name: str
    bounds: tuple[float, float, float, float]
    start: tuple[float, float, float]  # x, y, phi [rad]
    goal: tuple[float, float]
    goal_tolerance: float = 0.25
    view: float = 8.0
    polygons: tuple[Polygon, ...] = field(default=())
    source: str = ""
    start_line: int = 0
    goal_line: int = 0

    def of_kind(self, *kinds: str) -> list[Polygon]:
        return [p for p in self.polygons if p.kind in kinds]

    def to_json(self) -> dict:
        return {"name": self.name, "bounds": list(self.bounds), "start": list(self.start),
                "goal": list(self.goal), "goal_tolerance": self.goal_tolerance,
                "view": self.view, "polygons": [p.to_json() for p in self.polygons]}


def grid_nodes(bounds: tuple[float, float, float, float], grid: float = PLAN_GRID
               ) -> tuple[int, int]:
    """Nodes ``(nx, ny)`` of a distance grid of spacing ``grid`` over ``bounds``."""
    x0, y0, x1, y1 = bounds
    return int(math.ceil((x1 - x0) / grid)) + 1, int(math.ceil((y1 - y0) / grid)) + 1


def carve_nodes(points: np.ndarray, bounds: tuple[float, float, float, float],
                grid: float = PLAN_GRID) -> int:
    """Grid nodes whose distance to the polygon ``points`` is computed (its bounding box
    widened by ``GRID_REACH``, clipped to the grid)."""
    nx, ny = grid_nodes(bounds, grid)
    lo = np.floor((points.min(axis=0) - GRID_REACH - bounds[:2]) / grid)
    hi = np.ceil((points.max(axis=0) + GRID_REACH - bounds[:2]) / grid) + 1
    w = min(hi[0], nx) - max(lo[0], 0)
    h = min(hi[1], ny) - max(lo[1], 0)
    return int(max(w, 0) * max(h, 0))


def bundled_worlds() -> list[str]:
    return sorted(p.stem for p in WORLD_DIR.glob("*.world"))


def load_world(name_or_path: str | Path) -> World:
    """A bundled world by name, or a world file; one-line errors."""
    text = str(name_or_path)
    path = WORLD_DIR / f"{text}.world"
    if text in bundled_worlds():
        return read_world(path)
    p = Path(text)
    if not p.suffix and not p.exists():
        raise InputError(f"unknown world {text!r}; available: {', '.join(bundled_worlds())} "
                         "or a path to a .world file")
    return read_world(p)


def _numbers(path: Path, no: int, key: str, toks: list[str], counts: str) -> list[float]:
    out = []
    for t in toks:
        try:
            v = float(t)
        except ValueError:
            raise FileFormatError(path, no, f"{key}: expected numbers ({counts}), "
                                  f"got {t[:30]!r}") from None
        if not math.isfinite(v) or abs(v) > MAX_ABS:
            raise FileFormatError(path, no, f"{key}: expected finite numbers of magnitude "
                                  f"<= {MAX_ABS:g}, got {t[:30]}")
        out.append(v)
    return out


def read_world(path: str | Path) -> World:
    path = Path(path)
    lines = read_text_lines(path, "world file", MAX_WORLD_BYTES)
    seen: dict[str, int] = {}
    vals: dict[str, list[float]] = {}
    name = path.stem
    polygons: list[Polygon] = []
    vertices = 0
    for no, raw in enumerate(lines, start=1):
        toks = raw.split("#", 1)[0].split()
        if not toks:
            continue
        key, rest = toks[0], toks[1:]
        if key not in KEYWORDS:
            raise FileFormatError(path, no, f"unknown statement {key[:30]!r}; expected one of "
                                  f"{', '.join(KEYWORDS)}")
        if key in ("nostep", "obstacle", "hidden"):
            if len(polygons) >= MAX_POLYGONS:
                raise FileFormatError(path, no, f"expected at most {MAX_POLYGONS} polygons")
            if len(rest) < 6 or len(rest) % 2 or len(rest) > 2 * MAX_VERTICES:
                raise FileFormatError(path, no, f"{key}: expected x y pairs of 3 to "
                                      f"{MAX_VERTICES} vertices, got {len(rest)} numbers")
            vertices += len(rest) // 2
            if vertices > MAX_TOTAL_VERTICES:
                raise FileFormatError(path, no, f"{key}: expected at most "
                                      f"{MAX_TOTAL_VERTICES:,} polygon vertices in all")
            pts = np.array(_numbers(path, no, key, rest, "x y pairs")).reshape(-1, 2)
            why = simple_polygon_problem(pts)
            if why:
                raise FileFormatError(path, no, f"{key}: {why}")
            polygons.append(Polygon(key, pts, no))
            continue
        if key in seen:
            raise FileFormatError(path, no, f"{key}: given twice (first on line {seen[key]})")
        seen[key] = no
        if key == "name":
            if len(rest) != 1:
                raise FileFormatError(path, no, "name: expected one word")
            name = rest[0][:60]
            continue
        want = {"bounds": (4, 4, "xmin ymin xmax ymax"), "start": (3, 3, "x y phi_deg"),
                "goal": (2, 3, "x y [tolerance]"), "view": (1, 1, "radius")}[key]
        if not want[0] <= len(rest) <= want[1]:
            raise FileFormatError(path, no, f"{key}: expected {want[2]}, got {len(rest)} "
                                  "values")
        vals[key] = _numbers(path, no, key, rest, want[2])
    for key in ("start", "goal"):
        if key not in vals:
            raise FileFormatError(path, None, f"expected a '{key}' line")
    return _assemble(path, name, vals, seen, polygons)


def _assemble(path: Path, name: str, vals: dict, seen: dict, polygons: list) -> World:
    sx, sy, sphi = vals["start"]
    g = vals["goal"]
    tol = g[2] if len(g) == 3 else 0.25
    if tol <= 0:
        raise FileFormatError(path, seen["goal"], f"goal: expected a tolerance > 0, got {tol:g}")
    view = vals.get("view", [8.0])[0]
    if view <= 0:
        raise FileFormatError(path, seen["view"], f"view: expected a radius > 0, got {view:g}")
    if "bounds" in vals:
        x0, y0, x1, y1 = vals["bounds"]
        if not (x0 < x1 and y0 < y1):
            raise FileFormatError(path, seen["bounds"], "bounds: expected xmin < xmax and "
                                  "ymin < ymax")
    else:  # everything named, plus room for the legs
        pts = np.vstack([[sx, sy], g[:2], *[p.points for p in polygons]])
        (x0, y0), (x1, y1) = pts.min(axis=0) - 6.0, pts.max(axis=0) + 6.0
    bounds = (float(x0), float(y0), float(x1), float(y1))
    _check_size(path, seen.get("bounds"), bounds, polygons)
    for key, (px, py) in (("start", (sx, sy)), ("goal", g[:2])):
        if not (x0 < px < x1 and y0 < py < y1):
            raise FileFormatError(path, seen[key], f"{key}: expected a point inside the "
                                  f"bounds {bounds}, got ({px:g}, {py:g})")
        for p in polygons:
            if inside(np.array([px, py]), p.points):
                what = {"nostep": "a no-step zone", "hidden": "a hidden obstacle"}.get(
                    p.kind, "an obstacle")
                raise FileFormatError(path, seen[key], f"{key}: expected a point outside "
                                      f"every obstacle and no-step zone, got ({px:g}, {py:g})"
                                      f" inside {what} (line {p.line})")
    return World(name, bounds, (sx, sy, math.radians(sphi)), (g[0], g[1]), tol, view,
                 tuple(polygons), str(path), seen["start"], seen["goal"])


def _check_size(path: Path, line: int | None, bounds: tuple[float, float, float, float],
                polygons: list[Polygon]) -> None:
    """The planner's grids for ``bounds`` and the work of carving ``polygons`` into them
    within the documented limits (checked before any grid exists)."""
    nx, ny = grid_nodes(bounds)
    if nx * ny > MAX_GRID_NODES:
        given = "bounds" if line is not None else "the bounds (from the points named)"
        raise FileFormatError(path, line, f"{given}: expected a world of at most "
                              f"{MAX_GRID_NODES:,} nodes of {PLAN_GRID:g} units (e.g. 140 x 140"
                              f" units), got {bounds[2] - bounds[0]:.6g} x "
                              f"{bounds[3] - bounds[1]:.6g} units ({nx * ny:,.0f} nodes)")
    work = 0
    for p in polygons:
        work += carve_nodes(p.points, bounds) * len(p.points)
        if work > MAX_CARVE_WORK:
            raise FileFormatError(path, p.line, f"{p.kind}: the polygons up to here need "
                                  f"{work:,} node-edge distances to build the planner's grids,"
                                  f" at most {MAX_CARVE_WORK:,} (fewer vertices or smaller "
                                  "polygons)")
