"""The checker's own geometry for worlds (written apart from :mod:`.terrain` and
:mod:`.geometry`): point-in-polygon with :class:`matplotlib.path.Path`, exact distances
between the body rectangle and each obstacle polygon at densely sampled poses, and feet
against no-step zones and obstacles. Violations raise ``PlanViolationError`` (passed in, to
keep this module free of the checker's imports).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from matplotlib.path import Path as MplPath

TOL = 1e-6
POSE_STEP = 0.02  # [units] the body's outline moves at most this much between checked poses


def _point_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances of points p[n, 2] to segments a[m, 2]-b[m, 2], as [n, m]."""
    ab = b - a
    t = ((p[:, None, :] - a[None]) * ab[None]).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-300)
    t = np.clip(t, 0.0, 1.0)
    q = a[None] + t[..., None] * ab[None]
    return np.sqrt(((p[:, None, :] - q) ** 2).sum(-1))


class WorldGeometry:
    """The polygons of a plan's ``world`` section, with the state index each holds from."""

    def __init__(self, world: dict[str, Any], a: float, b: float) -> None:
        self.body_clearance = float(world.get("body_clearance", 0.0))
        self.foot_clearance = float(world.get("foot_clearance", 0.0))
        self.bounds = [float(v) for v in world["bounds"]]
        self.polys = [(p["kind"], np.array(p["points"], float), int(p.get("from", 0)))
                      for p in world["polygons"]]
        self.paths = [MplPath(np.vstack([pts, pts[:1]]), closed=True) for _, pts, _ in self.polys]
        self.half = np.array([a / 2, b / 2])
        # bounding boxes: a polygon far from every foot is skipped (one test for all)
        self.lo = np.array([pts.min(axis=0) for _, pts, _ in self.polys]).reshape(-1, 2)
        self.hi = np.array([pts.max(axis=0) for _, pts, _ in self.polys]).reshape(-1, 2)
        self.since = np.array([since for _, _, since in self.polys], dtype=float)

    def _rect(self, pose: np.ndarray) -> np.ndarray:
        (a2, b2), (c, s) = self.half, (math.cos(pose[2]), math.sin(pose[2]))
        local = np.array([[-a2, b2], [-a2, -b2], [a2, -b2], [a2, b2]])
        return pose[:2] + local @ np.array([[c, s], [-s, c]])

    def check_feet(self, feet: np.ndarray, index: int, where: str, error: type) -> None:
        x0, y0, x1, y1 = self.bounds
        for k, f in enumerate(feet):
            if not (x0 <= f[0] <= x1 and y0 <= f[1] <= y1):
                raise error(f"{where}: foot {k} is outside the world's bounds")
        reach = self.foot_clearance + 1e-3
        near = np.flatnonzero((self.since <= index) &
                              np.all(self.lo <= feet.max(axis=0) + reach, axis=1) &
                              np.all(self.hi >= feet.min(axis=0) - reach, axis=1))
        for i in near:
            (kind, pts, _), path = self.polys[i], self.paths[i]
            inside = path.contains_points(feet)
            d = _point_segment(feet, pts, np.roll(pts, -1, axis=0)).min(axis=1)
            bad = inside | (d < self.foot_clearance - TOL)
            if bad.any():
                k = int(np.argmax(bad))
                raise error(f"{where}: foot {k} is {'inside' if inside[k] else f'{d[k]:.3f} from'}"
                            f" a {kind} polygon (clearance {self.foot_clearance:g})")

    def check_body(self, poses: np.ndarray, index: int, where: str, error: type) -> None:
        """The body rectangle at every pose against every obstacle known by ``index``."""
        x0, y0, x1, y1 = self.bounds
        r = float(np.hypot(*self.half))
        lo, hi = poses[:, :2].min(axis=0) - r, poses[:, :2].max(axis=0) + r
        near = [i for i, (kind, pts, since) in enumerate(self.polys)
                if kind == "obstacle" and since <= index and
                np.all(pts.min(axis=0) <= hi + self.body_clearance + 1.0) and
                np.all(pts.max(axis=0) >= lo - self.body_clearance - 1.0)]
        for pose in poses:
            rect = self._rect(pose)
            if rect[:, 0].min() < x0 - TOL or rect[:, 0].max() > x1 + TOL or \
                    rect[:, 1].min() < y0 - TOL or rect[:, 1].max() > y1 + TOL:
                raise error(f"{where}: the body leaves the world's bounds")
            rpath = MplPath(np.vstack([rect, rect[:1]]), closed=True)
            for i in near:
                pts, path = self.polys[i][1], self.paths[i]
                d = min(_point_segment(rect, pts, np.roll(pts, -1, axis=0)).min(),
                        _point_segment(pts, rect, np.roll(rect, -1, axis=0)).min())
                overlap = path.contains_points(rect).any() or rpath.contains_points(pts).any()
                if overlap or d < self.body_clearance - TOL:
                    raise error(f"{where}: the body {'overlaps' if overlap else f'is {d:.3f} from'}"
                                f" an obstacle (clearance {self.body_clearance:g})")

    def poses(self, b0: np.ndarray, b1: np.ndarray) -> np.ndarray:
        """Poses along a body move, dense enough that the outline moves <= POSE_STEP."""
        r = float(np.hypot(*self.half))
        reach = float(np.hypot(*(b1[:2] - b0[:2]))) + r * abs(b1[2] - b0[2])
        t = np.linspace(0.0, 1.0, max(2, int(math.ceil(reach / POSE_STEP)) + 1))[:, None]
        return b0 + t * (b1 - b0)
