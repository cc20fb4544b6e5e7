"""An admissible A* heuristic for the paper-003 walking plans (cost: transitions, 1 each).

Let d = vzd - goal_tolerance be the distance still to cover. Only translations move the
body centre, each by at most T = 2 l_max sin(half width), the longest chord of a sector
along the body Y axis: at least ceil(d / T) translations remain.

Leg moves, by a potential argument. With the walking sense s (feet move by -s t in body Y
when the body walks s t), the *room* of foot i is T/2 + s * y_i, y_i its body-frame
offset from the hip along Y (|y_i| <= T/2 inside the sector). A translation by t lowers
every room by exactly t, so it lowers the summed room Phi by 4t; a leg move raises Phi by
at most T; a rotation by delta changes the feet by R(-delta), raising Phi by at most
G = sin(rho) |sum x| + (1 - cos rho) sum y (rho: the largest rotation all feet can make,
at most the sector's polar span about the body centre; |sum x| <= 2 (l_max - l_min cos hw);
sum y <= 2T). Covering d needs 4d <= Phi + T legs + G rotations, hence
legs + rotations >= (4d - Phi) / max(T, G).

``gain="analytic"`` uses that G (proved, but loose: 3.65 for Tab. 1). ``gain="sampled"``
uses twice the largest summed room gain of one rotation found by dense sampling of each
sector (about 0.9 for Tab. 1, so max(T, G) = T): six times tighter but resting on sampling.
With sense 0 (either direction) only the weaker stance bound is used: while a foot stays
at F the centre stays within r_max of F, so each foot moves ceil(d / 2 r_max) - 1 times.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import lru_cache

import numpy as np

from evomotion.studies.quadruped_plan.rules.model import QuadrupedModel

GAINS = ("analytic", "sampled")


def _polar_span(model: QuadrupedModel, leg: int, samples: int = 4000) -> float:
    """Upper bound [rad] of the spread of polar angles (about the body centre) over the
    sector of ``leg``: densely sampled boundary plus a 1e-3 rad safety margin."""
    hw, nom = model.sector_half_width, model.nominal_angle(leg)
    pts = []
    for k in range(samples + 1):
        u = k / samples
        beta = nom - hw + 2 * hw * u
        pts += [model.foot_at(leg, model.l_max, beta), model.foot_at(leg, model.l_min, beta)]
        length = model.l_min + (model.l_max - model.l_min) * u
        pts += [model.foot_at(leg, length, nom - hw), model.foot_at(leg, length, nom + hw)]
    ref = math.atan2(*reversed(model.foot_at(leg, model.l_max, nom)))
    offs = [(math.atan2(py, px) - ref + math.pi) % (2 * math.pi) - math.pi for px, py in pts]
    return max(offs) - min(offs) + 1e-3


@lru_cache(maxsize=8)
def heuristic_constants(model: QuadrupedModel) -> tuple[float, float, float]:
    """(T, D, G): the longest single translation; the longest centre travel per foot stance;
    the most one rotation can add to the summed foot room (module docstring)."""
    hw = model.sector_half_width
    chord = 2 * model.l_max * math.sin(hw)
    r_max = 0.0
    for leg, (hx, hy) in enumerate(model.hips):
        lo, hi = model.nominal_angle(leg) - hw, model.nominal_angle(leg) + hw
        toward = math.atan2(hy, hx)
        candidates = [lo, hi]
        for shift in (-2 * math.pi, 0.0, 2 * math.pi):
            if lo <= toward + shift <= hi:
                candidates.append(toward + shift)
        for beta in candidates:
            fx, fy = model.foot_at(leg, model.l_max, beta)
            r_max = max(r_max, math.hypot(fx, fy))
    rho = min(min(_polar_span(model, leg) for leg in range(4)), math.pi)
    sum_x = 2 * (model.l_max - model.l_min * math.cos(hw))
    sum_y = 2 * chord
    gain = math.sin(rho) * sum_x + (1 - math.cos(rho)) * sum_y
    return chord, 2 * r_max, gain


@lru_cache(maxsize=8)
def sampled_rotation_gain(model: QuadrupedModel, n_len: int = 31, n_ang: int = 41,
                          n_rot: int = 150) -> float:
    """Twice the largest rise of the summed foot room over one rotation, by sampling: for
    each sector a polar grid of feet, each foot turned along its arc (the rotation stops
    where the arc leaves the sector), the best foot per leg and rotation angle summed."""
    deltas = np.linspace(0.0, math.pi, n_rot + 1)[1:]
    best = 0.0
    for direction in (1.0, -1.0):
        total = np.zeros(n_rot)
        for leg in range(4):
            lengths, offs = np.meshgrid(np.linspace(model.l_min, model.l_max, n_len),
                                        np.linspace(-1, 1, n_ang) * model.sector_half_width)
            beta = model.nominal_angle(leg) + offs.ravel()
            hx, hy = model.hips[leg]
            px, py = hx + lengths.ravel() * np.cos(beta), hy + lengths.ravel() * np.sin(beta)
            ang = np.arctan2(py, px)[:, None] - direction * deltas[None, :]
            r = np.hypot(px, py)[:, None]
            qx, qy = r * np.cos(ang), r * np.sin(ang)
            ux = model.sides[leg] * (qx - hx)
            rel = np.hypot(ux, qy - hy)
            inside = ((rel >= model.l_min - 1e-9) & (rel <= model.l_max + 1e-9)
                      & (ux * math.tan(model.sector_half_width) >= np.abs(qy - hy) - 1e-9))
            reach = np.cumprod(inside, axis=1).astype(bool)  # whole arc inside so far
            d = direction * deltas[None, :]
            gain = np.sin(d) * px[:, None] + (1 - np.cos(d)) * py[:, None]
            total += np.where(reach, gain, -np.inf).max(axis=0)
        best = max(best, float(np.max(total[np.isfinite(total)], initial=0.0)))
    return 2.0 * best


def foot_room(model: QuadrupedModel, state: tuple[float, ...], sense: int) -> float:
    """Summed room of the four feet along the walking direction: sum of (T/2 -+ y_rel)."""
    half = model.l_max * math.sin(model.sector_half_width)
    hips = model.hips
    return sum(half + sense * (state[4 + 2 * i] - hips[i][1]) for i in range(4))


def plan_length_heuristic(model: QuadrupedModel, goal: tuple[float, float],
                          goal_tolerance: float, sense: int = -1, gain: str = "analytic",
                          shifts: bool = False) -> Callable[[tuple[float, ...]], float]:
    """Lower bound on the transitions still needed (see the module docstring).

    ``shifts``: the problem also has the body shifts of :mod:`.shifts` (at most
    ``SHIFT_MAX`` each): a shift lowers 4 d - Phi by at most 8 SHIFT_MAX (so the per-move
    gain is max(T, G, 8 SHIFT_MAX)) and covers at most SHIFT_MAX of the distance, so with
    L the leg/rotation/shift bound the translations are at least (d - SHIFT_MAX L) / T."""
    from evomotion.studies.quadruped_plan.rules.shifts import SHIFT_MAX

    if gain not in GAINS:
        raise ValueError(f"unknown rotation gain {gain!r}; available: {', '.join(GAINS)}")
    if shifts and sense == 0:
        raise ValueError("body shifts need a walking sense of -1 or +1")
    chord, stance, gain_value = heuristic_constants(model)
    if gain == "sampled":
        gain_value = sampled_rotation_gain(model)
    per_move = max(chord, gain_value, 8 * SHIFT_MAX if shifts else 0.0)
    cover = SHIFT_MAX if shifts else 0.0
    gx, gy = goal
    # foot_room(s) = room0 + sense * (sum of the feet's body y)
    room0 = 4 * model.l_max * math.sin(model.sector_half_width) - sense * sum(
        hy for _, hy in model.hips)
    ceil, hypot = math.ceil, math.hypot

    def bound(d: float, ysum: float) -> float:
        if d <= 0:
            return 0.0
        if sense == 0:
            return ceil(d / chord - 1e-9) + 4 * max(0, ceil(d / stance - 1e-9) - 1)
        legs = max(0, ceil((4 * d - (room0 + sense * ysum)) / per_move - 1e-9))
        return ceil(max(0.0, d - cover * legs) / chord - 1e-9) + legs

    def h(s: tuple[float, ...]) -> float:
        return bound(hypot(gx - s[0], gy - s[1]) - goal_tolerance, s[4] + s[6] + s[8] + s[10])

    def after_leg(s: tuple[float, ...], leg: int, fy: float) -> float:
        """h of ``s`` with foot ``leg`` moved to body y ``fy`` (same arithmetic as h)."""
        y = [s[4], s[6], s[8], s[10]]
        y[leg] = fy
        return bound(hypot(gx - s[0], gy - s[1]) - goal_tolerance, y[0] + y[1] + y[2] + y[3])

    h.after_leg = after_leg  # type: ignore[attr-defined]  # used by walk_search
    return h
