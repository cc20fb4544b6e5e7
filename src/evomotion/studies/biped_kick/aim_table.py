"""The kick's aim calibrated against the ball's place (issue 34).

Following the ball within the limits (:mod:`.adaptive`) leaves part of a ball's offset
unfollowed: a ball 1-2 cm from where the kick wants it still sends it 10-25 deg off its aim.
What the robot can still choose is the kick's commanded aim. So, as a team calibrates its kick
engine's direction against where the ball lies at the foot, this module measures it in
simulation and inverts it:

- :func:`measure` kicks the adaptive right-foot kick in the nominal world at every commanded
  aim ``c`` of a grid and every ball offset ``(dx, dy)`` of a grid (from where the kick at ``c``
  wants the ball): the direction (deg) and distance (m) the ball goes, an :class:`AimTable`.
- :func:`command` inverts it for kicks whose ball the robot sees: over the commands ``c`` from
  the table's range, 0.25 deg apart, whose evolved key poses keep every joint within its range
  and ``speed_margin`` x its no-load speed, the swing lengthened as far as the kick that follows
  the ball may (:mod:`.adaptive`, ``problem.adapt_max_stretch``; its foot rolled in the air
  as far as ``problem.adapt_foot_roll_rad`` allows), with the ball's offset from
  where ``c``'s kick wants it inside the table, the one of least cost ``max(|d - target| -
  TOLERANCE_DEG, 0) + SHIFT_COST |c - target|``, ``d`` the direction interpolated (trilinear):
  the nearest command predicted within ``TOLERANCE_DEG`` of the target, else the best trade of
  error and change (a command far from the target places the foot further from the ball's side,
  which can cost the robot its balance in a perturbed world); commands whose interpolated
  distance is under ``MIN_DISTANCE_M`` are excluded. None left: the target itself (the adaptive
  kick as before). A left-foot kick is the right one mirrored: its ball's y and its aims
  negated.
- :func:`write` / :func:`read`: the table as JSON (plain lists: a robot-side runner reads it
  without numpy).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.errors import FileFormatError, InputError
from evomotion.studies.biped_kick.adaptive import MAX_FOOT_ROLL_RAD, MAX_STRETCH

FORMAT = "evomotion-kick-aim-table/1"
#: the default grid: commanded aims (deg), ball offsets dx, dy (m)
AIMS_DEG = np.arange(-40.0, 40.01, 2.5)
DX_M = np.arange(-0.02, 0.0201, 0.01)
DY_M = np.arange(-0.06, 0.0601, 0.005)
COMMAND_STEP_DEG = 0.25
TOLERANCE_DEG = 2.0  # a predicted error within this costs nothing
SHIFT_COST = 0.1  # deg of predicted error per deg of command away from the target
MIN_DISTANCE_M = 1.0
#: a table file's bounds: commanded aims (deg), ball offsets (m), points per axis
MAX_TABLE_AIM_DEG = 90.0
MAX_TABLE_OFFSET_M = 0.2
MAX_TABLE_POINTS = 1000


@dataclass(frozen=True)
class AimTable:
    """Where the adaptive right-foot kick sends the ball: ``angle_deg[a, i, j]`` (direction
    from +x) and ``distance_m[a, i, j]`` (travel) for the commanded aim ``aims_deg[a]`` and the
    ball ``(dx_m[i], dy_m[j])`` from where that kick wants it (nominal world);
    ``max_stretch``, ``foot_roll_rad``: the ``problem.adapt_max_stretch`` and
    ``adapt_foot_roll_rad`` it was measured with (how much longer the following kick's swing
    and how far its foot's roll in the air might be, :mod:`.adaptive`; 1 and 0 in files
    written before those keys)."""

    aims_deg: np.ndarray
    dx_m: np.ndarray
    dy_m: np.ndarray
    angle_deg: np.ndarray
    distance_m: np.ndarray
    max_stretch: float = 1.0
    foot_roll_rad: float = 0.0

    def interpolate(self, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(direction, distance) at ``pts[n, 3]`` = (aim deg, dx m, dy m) inside the grid."""
        from scipy.interpolate import RegularGridInterpolator

        axes = (self.aims_deg, self.dx_m, self.dy_m)
        return (RegularGridInterpolator(axes, self.angle_deg)(pts),
                RegularGridInterpolator(axes, self.distance_m)(pts))


def measure(problem: Any, genome: np.ndarray, aims_deg: np.ndarray = AIMS_DEG,
            dx_m: np.ndarray = DX_M, dy_m: np.ndarray = DY_M) -> AimTable:
    """The table of ``problem``'s (a :class:`.problem.KickProblem`) kick ``genome`` (one batch
    of ``len(dx_m) * len(dy_m)`` kicks per aim; the default grid: 4 125 kicks, 4-5 min on 2
    cores)."""
    aims = np.asarray(aims_deg, dtype=float)
    dx, dy = np.meshgrid(np.asarray(dx_m, float), np.asarray(dy_m, float), indexing="ij")
    offsets = np.stack([dx.ravel(), dy.ravel()], axis=1)
    g = np.repeat(np.atleast_2d(genome), len(offsets), axis=0)
    angle = np.zeros((len(aims), *dx.shape))
    dist = np.zeros_like(angle)
    for a, aim in enumerate(aims):
        rad = np.full(len(g), np.radians(aim))
        k = problem.kicks(g, rad, problem.wanted_ball_xy(g, rad) + offsets, adapt=True)
        travel = k["travel"]
        angle[a] = np.degrees(np.arctan2(travel[:, 1], travel[:, 0])).reshape(dx.shape)
        dist[a] = np.hypot(travel[:, 0], travel[:, 1]).reshape(dx.shape)
    return AimTable(aims, np.asarray(dx_m, float), np.asarray(dy_m, float), angle, dist,
                    float(problem.cfg.adapt_max_stretch), float(problem.cfg.adapt_foot_roll_rad))


def within_limits(problem: Any, genome: np.ndarray, aims_deg: np.ndarray,
                  left: bool) -> np.ndarray:
    """Per commanded aim (right-foot frame), whether the kick as evolved, its swing lengthened
    by at most ``problem.cfg.adapt_max_stretch`` and its foot rolled in the air by at most
    ``problem.cfg.adapt_foot_roll_rad`` as a following kick may (:mod:`.adaptive`),
    keeps its key poses within every joint range and ``speed_margin`` x no-load speed (as
    played: mirrored for the left foot)."""
    from evomotion.studies.biped_kick.adaptive import evolved_stretch

    aims = np.asarray(aims_deg, dtype=float)
    g = np.repeat(np.atleast_2d(genome), len(aims), axis=0)
    return np.isfinite(evolved_stretch(problem, g, np.radians(aims),
                                       np.full(len(aims), bool(left))))


def command(table: AimTable, problem: Any, genome: np.ndarray, target_deg: float,
            ball_xy: np.ndarray, left_foot: bool = False) -> np.ndarray:
    """The commanded aim (deg, world: as :meth:`.problem.KickProblem.kicks` takes it) of each
    kick of ``genome`` at ``target_deg`` with its ball at ``ball_xy[n, 2]`` (world; the robot
    at the origin facing +x), by the module doc's rule."""
    check_following(table, problem.cfg)
    flip = -1.0 if left_foot else 1.0
    target = float(target_deg) * flip
    ball = np.asarray(ball_xy, dtype=float).reshape(-1, 2) * [1.0, flip]
    cands = np.arange(table.aims_deg[0], table.aims_deg[-1] + 1e-9, COMMAND_STEP_DEG)
    cands = cands[within_limits(problem, genome, cands, left_foot)]
    out = np.full(len(ball), target)
    if not cands.size:
        return out * flip
    g = np.repeat(np.atleast_2d(genome), len(cands), axis=0)
    rel = ball[:, None, :] - problem.wanted_ball_xy(g, np.radians(cands))[None]
    inside = ((rel[..., 0] >= table.dx_m[0]) & (rel[..., 0] <= table.dx_m[-1])
              & (rel[..., 1] >= table.dy_m[0]) & (rel[..., 1] <= table.dy_m[-1]))
    cost = np.full(inside.shape, np.inf)
    if inside.any():
        rows, cols = np.nonzero(inside)
        angle, dist = table.interpolate(np.column_stack([cands[cols], rel[rows, cols]]))
        c = (np.maximum(np.abs(angle - target) - TOLERANCE_DEG, 0.0)
             + SHIFT_COST * np.abs(cands[cols] - target))
        cost[rows, cols] = np.where(dist >= MIN_DISTANCE_M, c, np.inf)
    best = np.argmin(cost, axis=1)
    found = np.isfinite(cost[np.arange(len(ball)), best])
    out[found] = cands[best[found]]
    return out * flip


def check_following(table: AimTable, cfg: Any, what: str = "kick aim table") -> None:
    """One line unless ``table`` was measured with the kick config ``cfg``'s
    ``adapt_max_stretch`` and ``adapt_foot_roll_rad`` (how the kick follows the ball decides
    where it sends it)."""
    for key, had in (("adapt_max_stretch", table.max_stretch),
                     ("adapt_foot_roll_rad", table.foot_roll_rad)):
        if had != getattr(cfg, key):
            raise InputError(f"{what}: measured with problem.{key} = {had:g}, the kick "
                             f"follows the ball with {getattr(cfg, key):g}: measure the table "
                             "anew (evomotion biped-kick calibrate)")


def read_or_measure(path: Path | None, problem: Any, genome: np.ndarray, source: str = ""
                    ) -> AimTable:
    """The table in the file ``path`` if it exists (measured with ``problem``'s following, one
    line otherwise: :func:`check_following`), else measured (:func:`measure`) and written
    there (``path`` None: measured only)."""
    if path is not None and Path(path).exists():
        table = read(path)
        check_following(table, problem.cfg, f"--table {path}")
        return table
    table = measure(problem, genome)
    if path is not None:
        write(path, table, source)
    return table


def write(path: str | Path, table: AimTable, source: str = "") -> Path:
    from evomotion.outfile import write_json

    return write_json(path, {"format": FORMAT, "kick": source,
                             "aims_deg": table.aims_deg, "dx_m": table.dx_m,
                             "dy_m": table.dy_m, "angle_deg": table.angle_deg,
                             "distance_m": table.distance_m,
                             "adapt_max_stretch": table.max_stretch,
                             "adapt_foot_roll_rad": table.foot_roll_rad}, "kick aim table")


def read(path: str | Path) -> AimTable:
    """The table written by :func:`write`; anything else is one :class:`FileFormatError`."""
    from evomotion.textio import read_json

    rec = read_json(path, "kick aim table")
    if not isinstance(rec, dict) or rec.get("format") != FORMAT:
        raise FileFormatError(path, None, f"expected a kick aim table (format {FORMAT!r})")
    axes = []
    for key, bound in (("aims_deg", MAX_TABLE_AIM_DEG), ("dx_m", MAX_TABLE_OFFSET_M),
                       ("dy_m", MAX_TABLE_OFFSET_M)):
        v = _array(path, rec, key, 1)
        if v.size < 2 or np.any(np.diff(v) <= 0):
            raise FileFormatError(path, None, f"key {key!r}: at least 2 increasing numbers")
        if v.size > MAX_TABLE_POINTS or np.abs(v).max() > bound:
            raise FileFormatError(path, None, f"key {key!r}: at most {MAX_TABLE_POINTS} "
                                              f"numbers within +-{bound:g}")
        axes.append(v)
    shape = tuple(v.size for v in axes)
    grids = [_array(path, rec, key, 3) for key in ("angle_deg", "distance_m")]
    for key, v in zip(("angle_deg", "distance_m"), grids, strict=True):
        if v.shape != shape:
            raise FileFormatError(path, None, f"key {key!r}: a {shape[0]} x {shape[1]} x "
                                              f"{shape[2]} grid (aims x dx x dy)")
    # files before these keys: the evolved timing, a level sole
    stretch = _bounded(path, rec, "adapt_max_stretch", 1.0, 1.0, MAX_STRETCH)
    roll = _bounded(path, rec, "adapt_foot_roll_rad", 0.0, 0.0, MAX_FOOT_ROLL_RAD)
    (aims, dx, dy), (angle, distance) = axes, grids
    return AimTable(aims, dx, dy, angle, distance, stretch, roll)


def _bounded(path: str | Path, rec: dict, key: str, default: float, lo: float, hi: float
             ) -> float:
    """``rec[key]`` (``default`` when absent): a number from ``lo`` to ``hi``, else one
    :class:`FileFormatError`."""
    v = rec.get(key, default)
    if isinstance(v, bool) or not isinstance(v, int | float) or not lo <= v <= hi:
        raise FileFormatError(path, None, f"key {key!r}: a number from {lo:g} to {hi:g}")
    return float(v)


def _array(path: str | Path, rec: dict, key: str, ndim: int) -> np.ndarray:
    what = "a list of numbers" if ndim == 1 else f"a {ndim}-level nested list of numbers"
    try:
        v = np.array(rec.get(key), dtype=float)
    except (TypeError, ValueError):
        raise FileFormatError(path, None, f"key {key!r}: {what}") from None
    if v.ndim != ndim or not np.all(np.isfinite(v)):
        raise FileFormatError(path, None, f"key {key!r}: {what}, all finite")
    return v
