"""World files for quadruped plans: bounds, start, goal, no-step zones and obstacles.

A world is a UTF-8 text file, one statement per line, lengths in the seed's units, angles in
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
(``corridor``, ``gaps``, ``field``) are found by name (:func:`load_world`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from evomotion.errors import FileFormatError, InputError
from evomotion.studies.quadruped_plan.geometry import simple_polygon_problem
from evomotion.textio import read_text_lines

WORLD_DIR = Path(__file__).with_name("worlds")
MAX_WORLD_BYTES = 1 << 20
MAX_ABS = 1e4  # [units]
MAX_VERTICES = 1000
MAX_POLYGONS = 500
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
    for key, (px, py) in (("start", (sx, sy)), ("goal", g[:2])):
        if not (x0 < px < x1 and y0 < py < y1):
            raise FileFormatError(path, seen[key], f"{key}: expected a point inside the "
                                  f"bounds {bounds}, got ({px:g}, {py:g})")
    return World(name, bounds, (sx, sy, math.radians(sphi)), (g[0], g[1]), tol, view,
                 tuple(polygons), str(path), seen["start"], seen["goal"])
