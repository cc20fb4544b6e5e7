"""Independent brute-force references for the grid-path tests (exact rational arithmetic).

Validity: every cell of the map and of a ring around it (the outside counts as blocked) is
clipped against the segment with Liang-Barsky in ``Fraction`` arithmetic; the clip
parameters split the segment into pieces, and each split point and piece midpoint is
classified exactly by the closed cells that contain it. ``closed`` rule: no such cell may be
blocked; ``open`` rule: not all of them may be blocked (else the point is interior to the
union of blocked squares).
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from scipy.sparse import lil_matrix
from scipy.sparse.csgraph import dijkstra


def _clip(p0, p1, x0, y0):
    t0, t1 = Fraction(0), Fraction(1)
    for p, d, lo, hi in ((p0[0], p1[0] - p0[0], x0, x0 + 1), (p0[1], p1[1] - p0[1], y0, y0 + 1)):
        if d == 0:
            if p < lo or p > hi:
                return None
            continue
        a, b = (lo - p) / d, (hi - p) / d
        a, b = min(a, b), max(a, b)
        t0, t1 = max(t0, a), min(t1, b)
        if t0 > t1:
            return None
    return t0, t1


def _containing(v):
    k = v.numerator // v.denominator  # floor
    return (k - 1, k) if v == k else (k,)


def valid_reference(blocked, p0, p1, rule):
    h, w = blocked.shape
    p0 = tuple(Fraction(v) for v in p0)
    p1 = tuple(Fraction(v) for v in p1)
    if not all(0 <= p[0] <= w and 0 <= p[1] <= h for p in (p0, p1)):
        return False  # the map is convex: a segment is inside iff its ends are

    def is_blocked(x, y):
        return not (0 <= x < w and 0 <= y < h) or bool(blocked[y, x])

    ts = {Fraction(0), Fraction(1)}
    for y in range(-1, h + 1):
        for x in range(-1, w + 1):
            c = _clip(p0, p1, x, y)
            if c is not None:
                ts.update(c)
    ts = sorted(ts)
    pts = ts + [(a + b) / 2 for a, b in zip(ts[:-1], ts[1:], strict=True)]
    for t in pts:
        px = p0[0] + t * (p1[0] - p0[0])
        py = p0[1] + t * (p1[1] - p0[1])
        cells = [is_blocked(cx, cy) for cx in _containing(px) for cy in _containing(py)]
        if (all(cells) if rule == "open" else any(cells)):
            return False
    return True


def visibility_reference(blocked, nodes, s, t, rule):
    """Dijkstra (scipy) on the complete visibility graph of ``nodes`` with exact validity."""
    n = len(nodes)
    g = lil_matrix((n, n))
    for i in range(n):
        for j in range(i + 1, n):
            if valid_reference(blocked, nodes[i], nodes[j], rule):
                d = float(np.hypot(*(np.asarray(nodes[i]) - np.asarray(nodes[j]))))
                g[i, j] = g[j, i] = d
    return float(dijkstra(g.tocsr(), directed=False, indices=s)[t])


def octile_reference(blocked, start, goal):
    """Dijkstra (scipy) on the 8-connected grid without corner cutting."""
    h, w = blocked.shape
    g = lil_matrix((h * w, h * w))
    for y in range(h):
        for x in range(w):
            if blocked[y, x]:
                continue
            for dx in (-1, 0, 1):
                for dy in (-1, 0, 1):
                    nx, ny = x + dx, y + dy
                    if (dx, dy) == (0, 0) or not (0 <= nx < w and 0 <= ny < h):
                        continue
                    if blocked[ny, nx] or (dx and dy and (blocked[y, nx] or blocked[ny, x])):
                        continue
                    g[y * w + x, ny * w + nx] = np.hypot(dx, dy)
    return float(dijkstra(g.tocsr(), indices=start[1] * w + start[0])[goal[1] * w + goal[0]])
