"""The kick that follows the ball within the robot's limits (issue 34).

A robot that sees the ball moves its kicking foot's lift and kick points by the ball's offset
from where the kick wants it (:func:`.motion.foot_trajectories`' ``ball_shift``), as the kick
engines of RoboCup teams adjust the swing to the perceived ball. The whole offset is not always
reachable: a ball outboard of the kicking foot asks for more ankle roll than the joint has, a
longer swing for more speed than the motors give. So each kick takes the largest fraction

    λ ∈ {1, 1 − 1/S, …, 1/S, 0}   (S = :data:`FRACTIONS`)

of the offset whose 20 ms key poses keep every joint within its range and ``speed_margin`` x
its motor's no-load speed (:func:`.motion.limit_excess` zero, the problem's own constraint), and
``λ = 0`` (the kick as evolved) when none does. Only the key poses are computed for this (the IK,
no simulation).

**Slowing down instead** (``max_stretch`` > 1): a kick engine that must not outrun its motors
takes a swing longer rather than shorter. The swing's three phases (lift, kick, retract: the
genes :data:`SWING`) are a path in space played on a clock; lengthening them by ``s`` leaves
the path, so the joint ranges, and divides every swing joint's speed by about ``s``. So a
fraction ``λ`` is also taken when its poses keep the ranges and stay within the motor speeds
once the swing is lengthened by an ``s ≤ max_stretch`` that does (:func:`fitting_stretch`:
``s`` raised from 1 by the largest speed ratio left, checked on the 20 ms poses, until they
pass), down to ``λ = 0``, the kick as evolved, which may need slowing down too. The evolved
kick runs near its motors' speeds (the shipped one at 0.99 of the kicking hip's at ±30°), so a
few percent longer swing reaches commands and ball offsets the evolved timing cannot. ``s =
1``: the kick's own timing, bit for bit.

**The foot rolls in the air** (``max_roll`` > 0, ``problem.adapt_foot_roll_rad``): the kick
keeps the kicking sole level, so a ball outboard of the foot asks the ankle to roll against
the hip's roll beyond its range (the NAO's right ankle, 0.398 rad, is what cut the following
of balls 1-2 cm outboard to a fraction and sent them 10-15 deg off a ±20-30 deg aim). In the
air the sole need not be level: :func:`rolled_in_air` clips the kicking ankle's roll into its
range where it leaves it by at most ``max_roll`` while the foot is off the ground (from the
lift's start to the retract's end), and leaves it (so the fraction is refused) where it
would leave it by more. The ankle roll is the leg's last joint, so the ankle's path is
unchanged; the sole tilts about it by at most ``max_roll``, its outer edge up (its contact
points move by a few millimetres). ``max_roll = 0``: the level sole, bit for bit. A kick whose
ankle stays within its range is unchanged too; one whose evolved (λ = 0) poses leave it by
at most ``max_roll`` in the air is rolled, where it used to be played over the limit (not the
shipped kick: its kicking ankle's roll stays at 0.33-0.38 of 0.398 rad from −40 to +40°).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from evomotion.errors import InputError
from evomotion.studies.biped_kick.motion import GENE_INDEX, SETTLE_S, gene, key_times, limit_excess

#: the offset's fractions tried, from the whole offset down (S + 1 values)
FRACTIONS = 10
#: the swing's phase durations (genes) a stretch lengthens
SWING = ("t_lift_s", "t_kick_s", "t_retract_s")
#: the longest swing a following kick may be set to take (x its own; problem.adapt_max_stretch)
MAX_STRETCH = 2.0
#: tries of :func:`fitting_stretch` (each raises ``s`` by the speed ratio still left)
STRETCH_TRIES = 8
#: the most a kicking foot may be set to roll in the air (rad; problem.adapt_foot_roll_rad)
MAX_FOOT_ROLL_RAD = 0.5

KeysOf = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


def retimed(genomes: np.ndarray, stretch: np.ndarray) -> np.ndarray:
    """``genomes[n, d]`` with the swing's phases (:data:`SWING`) ``stretch[n]`` times longer."""
    out = np.array(genomes, dtype=float, copy=True)
    cols = [GENE_INDEX[name] for name in SWING]
    out[:, cols] *= np.asarray(stretch, dtype=float)[:, None]
    return out


def fitting_stretch(keys_of: KeysOf, rows: np.ndarray, shift: np.ndarray, speed_margin: float,
                    limits: tuple | None, max_stretch: float) -> np.ndarray:
    """Per kick ``rows[i]`` with ``shift[i]``: a swing stretch ``s`` in ``[1, max_stretch]``
    whose key poses (``keys_of(rows, shift, s)``) are within the limits, found by raising ``s``
    from 1 by the speed ratio left (the 20 ms poses sample the path anew at each ``s``, so the
    ratio does not fall exactly as 1 / s: not always the smallest such ``s``), the last try at
    ``max_stretch`` itself; nan where none is found (a joint out of range, or more than
    ``max_stretch`` needed)."""
    s = np.ones(len(rows))
    out = np.full(len(rows), np.nan)
    todo = np.arange(len(rows))
    for _ in range(STRETCH_TRIES):
        if not todo.size:
            break
        range_x, speed_x, ratio = limit_excess(keys_of(rows[todo], shift[todo], s[todo]),
                                               speed_margin, limits)
        ok = (range_x <= 0) & (speed_x <= 0)
        out[todo[ok]] = s[todo[ok]]
        at_most = s[todo] >= max_stretch  # tried at the cap: no further
        # raise s by the ratio left (and a little: the poses sample the path anew)
        s[todo] = np.minimum(s[todo] * np.maximum(ratio, 1.0) * (1.0 + 1e-3), max_stretch)
        todo = todo[~ok & (range_x <= 0) & ~at_most]
    return out


def reachable_shift(keys_of: KeysOf, shift: np.ndarray, speed_margin: float,
                    limits: tuple | None, max_stretch: float = 1.0
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(the shift each kick uses ``[n, 2]``, its fraction λ ``[n]``, its swing stretch ``[n]``)
    of the wanted ``shift`` ``[n, 2]`` (m); ``keys_of(rows, shift_rows, stretch_rows)`` gives
    those kicks' key poses ``[r, K, nu]`` as played (mirrored for a left-foot kick), ``limits``
    the robot's (:func:`.motion.limit_excess`); ``max_stretch``: the longest swing allowed
    (module doc; 1: the evolved timing only). A kick within the limits at no fraction keeps
    λ = 0 and its own timing: the kick as evolved, its foot rolled in the air where
    ``keys_of`` rolls it (:func:`rolled_in_air`)."""
    shift = np.asarray(shift, dtype=float)
    n = len(shift)
    frac = np.zeros(n)
    stretch = np.ones(n)
    todo = np.arange(n)
    # down to λ = 0, the kick as evolved, which may need slowing down too (a command the
    # evolved timing is too fast for); a kick within the limits nowhere keeps λ = 0, s = 1
    for lam in np.linspace(1.0, 0.0, FRACTIONS + 1):
        if not todo.size:
            break
        s = fitting_stretch(keys_of, todo, lam * shift[todo], speed_margin, limits,
                            max_stretch)
        ok = np.isfinite(s)
        frac[todo[ok]] = lam
        stretch[todo[ok]] = s[ok]
        todo = todo[~ok]
    return shift * frac[:, None], frac, stretch


def rolled_in_air(keys: np.ndarray, g: np.ndarray, times_s: np.ndarray,
                  swing_roll: tuple[int, float, float] | None, max_roll: float) -> np.ndarray:
    """``keys[n, T, nu]`` (right-foot kicks of genomes ``g`` on ``times_s``) with the kicking
    ankle's roll (``swing_roll``: its column and range, or None: unchanged) clipped into its
    range while the foot is in the air (after the lift's start, before the retract's end),
    where it leaves the range by at most ``max_roll`` (rad; module doc). In place; returned."""
    if swing_roll is None or max_roll <= 0.0:
        return keys
    col, lo, hi = swing_roll
    t = np.asarray(times_s, dtype=float)[None, :] - SETTLE_S
    lift = gene(g, "t_shift_s")[:, None]
    down = lift + sum(gene(g, name)[:, None] for name in SWING)
    roll = keys[..., col]
    inside = np.clip(roll, lo, hi)
    take = (t > lift) & (t < down) & (np.abs(roll - inside) <= max_roll)
    keys[..., col] = np.where(take, inside, roll)
    return keys


def following_keys(kicker: Any, g: np.ndarray, kt: np.ndarray, aims_k: np.ndarray,
                   shift: np.ndarray | None, max_roll: float
                   ) -> tuple[np.ndarray, np.ndarray | None]:
    """The right-foot kicks of genomes ``g`` at aims ``aims_k`` on the key times ``kt`` as
    played (``kicker.joint_targets``' key poses ``[n, K, nu]`` and IK error): with a ``shift``
    (the kicking foot's: a kick that follows the ball) the foot rolled in the air by at most
    ``max_roll`` (:func:`rolled_in_air`), without one (None) as evolved. What the limit check
    (:func:`played_keys`) and the rollout (:meth:`.problem.KickProblem.controls`) both see."""
    keys, ik_error = kicker.joint_targets(g, kt, aims_k, shift)
    if shift is not None:
        rolled_in_air(keys, g, kt, kicker.swing_roll, max_roll)
    return keys, ik_error


def played_keys(kicker: Any, g: np.ndarray, kt: np.ndarray, aims_k: np.ndarray,
                shift: np.ndarray | None, left: np.ndarray, *, max_roll: float
                ) -> np.ndarray:
    """The key poses ``[n, K, nu]`` of :func:`following_keys`, mirrored where ``left``."""
    keys, _ = following_keys(kicker, g, kt, aims_k, shift, max_roll)
    if left.any():
        keys[left] = kicker.mirror(keys[left])
    return keys


def left_flags(left_foot: Any, n: int, mirror: Any, robot: str) -> np.ndarray:
    """``left_foot`` (one flag or ``n``) as ``n`` flags; a one-line error for anything else
    or for a left-foot kick on a kicker without a mirror image (``mirror`` None)."""
    flags = np.asarray(left_foot)
    if flags.dtype != bool or flags.ndim > 1 or flags.size not in (1, n):
        raise InputError(f"left-foot kick: expected true/false, once or once per kick ({n}), "
                         f"got {' '.join(repr(left_foot).split())[:60]}")
    left = np.broadcast_to(flags.reshape(-1), (n,))
    if left.any() and mirror is None:
        raise InputError(f"left-foot kick: {robot}'s kicker has no mirror image (the NAO's "
                         "closed-form kick only)")
    return left


def _keys_of(problem: Any, g: np.ndarray, aims_k: np.ndarray, left: np.ndarray
             ) -> tuple[KeysOf, float]:
    """(``keys_of`` of :func:`reachable_shift` for a :class:`.problem.KickProblem`'s kicks,
    its ``problem.cfg.adapt_max_stretch``)."""
    kicker = problem.kicker
    most = float(problem.cfg.adapt_max_stretch)
    roll = float(problem.cfg.adapt_foot_roll_rad)
    # the batch's key times, long enough for its longest swing: every kick on the same grid
    kt = key_times(retimed(g, np.full(len(g), max(most, 1.0))))

    def keys_of(rows: np.ndarray, s: np.ndarray, stretch: np.ndarray) -> np.ndarray:
        return played_keys(kicker, retimed(g[rows], stretch), kt, aims_k[rows], s,
                           left[rows], max_roll=roll)

    return keys_of, most


def followed_shift(problem: Any, g: np.ndarray, aims_k: np.ndarray, shift: np.ndarray,
                   left: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`reachable_shift` for a :class:`.problem.KickProblem`'s kicks of genomes ``g``
    at the right-foot aims ``aims_k`` (mirrored where ``left``), with its
    ``problem.cfg.adapt_max_stretch``."""
    keys_of, most = _keys_of(problem, g, aims_k, left)
    return reachable_shift(keys_of, shift, problem.cfg.speed_margin, problem.kicker.limits,
                           most)


def following(problem: Any, g: np.ndarray, aims_k: np.ndarray, ball_k: np.ndarray,
              left: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The kicks of genomes ``g`` at the right-foot aims ``aims_k`` that see their balls at
    ``ball_k[n, 2]`` (right-foot frame): (their genomes, the swing slowed where the motors need
    it; the shift each swing follows; its fraction of the ball's offset; the stretch)."""
    offset = ball_k - problem.wanted_ball_xy(g, aims_k)
    shift, frac, stretch = followed_shift(problem, g, aims_k, offset, left)
    return retimed(g, stretch), shift, frac, stretch


def evolved_stretch(problem: Any, g: np.ndarray, aims_k: np.ndarray, left: np.ndarray
                    ) -> np.ndarray:
    """Per kick of genomes ``g`` at the right-foot aims ``aims_k`` with the ball in its place:
    the swing stretch (:func:`fitting_stretch`, at most ``problem.cfg.adapt_max_stretch``)
    within every joint range and motor speed, nan where none is."""
    keys_of, most = _keys_of(problem, g, aims_k, left)
    rows = np.arange(len(g))
    return fitting_stretch(keys_of, rows, np.zeros((len(g), 2)), problem.cfg.speed_margin,
                           problem.kicker.limits, most)
