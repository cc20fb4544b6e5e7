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
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from evomotion.errors import InputError
from evomotion.studies.biped_kick.motion import key_times, limit_excess

#: the offset's fractions tried, from the whole offset down (S + 1 values)
FRACTIONS = 10


def reachable_shift(keys_of: Callable[[np.ndarray, np.ndarray], np.ndarray],
                    shift: np.ndarray, speed_margin: float, limits: tuple | None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """(the shift each kick uses ``[n, 2]``, its fraction λ ``[n]``) of the wanted ``shift``
    ``[n, 2]`` (m); ``keys_of(rows, shift_rows)`` gives those kicks' key poses ``[r, K, nu]``
    as played (mirrored for a left-foot kick), ``limits`` the robot's
    (:func:`.motion.limit_excess`)."""
    shift = np.asarray(shift, dtype=float)
    n = len(shift)
    frac = np.zeros(n)
    todo = np.arange(n)
    for lam in np.linspace(1.0, 0.0, FRACTIONS + 1)[:-1]:
        if not todo.size:
            break
        ok = keys_within_limits(keys_of(todo, lam * shift[todo]), speed_margin, limits)
        frac[todo[ok]] = lam
        todo = todo[~ok]
    return shift * frac[:, None], frac


def keys_within_limits(keys: np.ndarray, speed_margin: float, limits: tuple | None
                       ) -> np.ndarray:
    """Per kick of key poses ``keys[n, K, nu]``: within every joint range and ``speed_margin``
    x its motor's no-load speed (:func:`.motion.limit_excess` zero)."""
    range_x, speed_x, _ = limit_excess(keys, speed_margin, limits)
    return (range_x <= 0) & (speed_x <= 0)


def played_keys(kicker: Any, g: np.ndarray, kt: np.ndarray, aims_k: np.ndarray,
                shift: np.ndarray | None, left: np.ndarray) -> np.ndarray:
    """The key poses ``[n, K, nu]`` of the right-foot kicks of genomes ``g`` at aims
    ``aims_k`` on the key times ``kt`` (``shift``: the kicking foot's, or None), as played:
    mirrored where ``left``."""
    keys, _ = kicker.joint_targets(g, kt, aims_k, shift)
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


def followed_shift(problem: Any, g: np.ndarray, aims_k: np.ndarray, shift: np.ndarray,
                   left: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`reachable_shift` for a :class:`.problem.KickProblem`'s kicks of genomes ``g``
    at the right-foot aims ``aims_k`` (mirrored where ``left``)."""
    kicker = problem.kicker
    kt = key_times(g)  # the batch's key times: every kick's poses on the same grid

    def keys_of(rows: np.ndarray, s: np.ndarray) -> np.ndarray:
        return played_keys(kicker, g[rows], kt, aims_k[rows], s, left[rows])

    return reachable_shift(keys_of, shift, problem.cfg.speed_margin, kicker.limits)
