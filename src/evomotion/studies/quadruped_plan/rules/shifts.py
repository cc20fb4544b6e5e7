"""Body shifts (rules 28-31, beyond the paper): sway the body over three feet to free a leg.

Statically stable walkers move the body over the triangle of the three feet that stay down
before they lift the fourth. The paper's rules only translate along the walking axis, and its
stances often hold the centre exactly on a diagonal (margin 0), so a landing error of a few
hundredths of a unit can leave no leg that may be lifted. With ``shifts`` on, a
:class:`.rules.WalkProblem` adds, for every leg k that may not be lifted, **rule 28 + k**:
translate the body (no rotation, feet fixed) by the shortest vector, along the inward normal
of a triangle edge the centre lies beyond or towards the triangle's incentre, that gives leg
k the margin ``model.min_margin + SHIFT_MARGIN``, if that is at most ``SHIFT_MAX`` and every
foot stays in its sector on the way. Exact: the margin is linear in the shift along a
direction, and a straight foot path stays in an annular sector when its ends do and it
keeps ``l_min`` from the hip.

The A* heuristic stays admissible with shifts (:mod:`.heuristic`, ``shifts=True``): a
shift of length s changes 4 d - Phi by at most 8 s <= max(T, G), and the body distance it
covers is charged against the translations.
"""

from __future__ import annotations

import math

from evomotion.studies.quadruped_plan.rules.model import QuadrupedModel

SHIFT_RULE = 28  # rules 28-31: free leg rule - 28
SHIFT_MAX = 0.3  # [units] 8 * SHIFT_MAX = 2.4 < T = 2.83 (heuristic)
SHIFT_MARGIN = 0.02  # [units] margin beyond model.min_margin after a shift


def _edges(tri: list[tuple[float, float]]) -> list[tuple[float, float, float]]:
    """Inward unit normals (nx, ny) and signed distance of the origin, per edge."""
    (ax, ay), (bx, by), (cx, cy) = tri
    orient = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    sign = 1.0 if orient > 0 else -1.0
    out = []
    for (px, py), (qx, qy) in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
        ex, ey = qx - px, qy - py
        n = math.hypot(ex, ey)
        if n == 0:
            return []
        nx, ny = -ey * sign / n, ex * sign / n
        out.append((nx, ny, -(nx * px + ny * py)))  # distance of the origin, > 0 inside
    return out


def _length(edges: list, ux: float, uy: float, want: float) -> float | None:
    """Shortest t >= 0 with every edge distance of t * u at least ``want``."""
    lo, hi = 0.0, math.inf
    for nx, ny, d in edges:
        rate = nx * ux + ny * uy
        if rate > 1e-12:
            lo = max(lo, (want - d) / rate)
        elif rate < -1e-12:
            hi = min(hi, (d - want) / -rate)
        elif d < want:
            return None
    return lo if lo <= hi else None


def _path_ok(model: QuadrupedModel, s: tuple, bx: float, by: float) -> bool:
    """Every foot's straight path by (-bx, -by) (body frame) stays in its sector."""
    lmin2 = model.l_min * model.l_min
    for leg, (hx, hy) in enumerate(model.hips):
        px, py = s[3 + 2 * leg], s[4 + 2 * leg]
        if not model.in_workspace(leg, px - bx, py - by):
            return False
        rx, ry = px - hx, py - hy  # the closest approach to the hip along the path
        n2 = bx * bx + by * by
        u = min(1.0, max(0.0, (rx * bx + ry * by) / n2)) if n2 > 0 else 0.0
        cx, cy = rx - u * bx, ry - u * by
        if cx * cx + cy * cy < lmin2 - 1e-9:
            return False
    return True


def shift_moves(model: QuadrupedModel, s: tuple, liftable: list[bool],
                cache: dict | None = None) -> list[tuple[int, float, float]]:
    """``(rule, dx, dy)`` world shifts of the body freeing each leg that may not be lifted.
    They depend on the body-frame feet alone, so ``cache`` may memoise them."""
    key = s[3:11]
    local = None if cache is None else cache.get(key)
    if local is None:
        local = _body_shifts(model, s, liftable)
        if cache is not None:
            if len(cache) >= 200_000:
                cache.clear()
            cache[key] = local
    c, sn = math.cos(s[2]), math.sin(s[2])
    return [(rule, c * bx - sn * by, sn * bx + c * by) for rule, bx, by in local]


def _body_shifts(model: QuadrupedModel, s: tuple, liftable: list[bool]
                 ) -> list[tuple[int, float, float]]:
    out = []
    want = model.min_margin + SHIFT_MARGIN
    feet = [(s[3 + 2 * i], s[4 + 2 * i]) for i in range(4)]
    for leg in range(4):
        if liftable[leg]:
            continue
        tri = [f for i, f in enumerate(feet) if i != leg]
        edges = _edges(tri)
        if not edges:
            continue
        dirs = [(nx, ny) for nx, ny, d in edges if d < want]
        w = [math.dist(tri[(k + 1) % 3], tri[(k + 2) % 3]) for k in range(3)]
        ix = sum(wk * p[0] for wk, p in zip(w, tri, strict=True)) / sum(w)
        iy = sum(wk * p[1] for wk, p in zip(w, tri, strict=True)) / sum(w)
        if math.hypot(ix, iy) > 1e-12:
            dirs.append((ix / math.hypot(ix, iy), iy / math.hypot(ix, iy)))
        best = None
        for ux, uy in dirs:
            t = _length(edges, ux, uy, want + 1e-9)
            if t is None or t <= 0 or t > SHIFT_MAX or (best is not None and t >= best[0]):
                continue
            if _path_ok(model, s, t * ux, t * uy):
                best = (t, ux, uy)
        if best is not None:
            t, ux, uy = best
            out.append((SHIFT_RULE + leg, t * ux, t * uy))
    return out


def shifted(s: tuple, dx: float, dy: float) -> tuple[float, ...]:
    """The 11 values of ``s`` with the body moved by world (dx, dy), feet fixed."""
    c, sn = math.cos(s[2]), math.sin(s[2])
    bx, by = c * dx + sn * dy, -sn * dx + c * dy
    feet: list[float] = []
    for leg in range(4):
        feet += (s[3 + 2 * leg] - bx, s[4 + 2 * leg] - by)
    return (s[0] + dx, s[1] + dy, s[2], *feet)
