"""Unseen worlds for the walker's tests: random polygon fields drawn from a seed.

A field is ``WIDTH`` x ``HEIGHT`` units: the robot starts at the west edge facing east, the
goal lies at the east edge, and rocks (star-shaped polygons, hence simple) and puddles
(no-step rectangles) are scattered between them, kept clear of the start and the goal; one
rock is hidden. The same seed always gives the same text.
"""

from __future__ import annotations

import math

import numpy as np

WIDTH, HEIGHT = 36.0, 24.0


def _star(rng: np.random.Generator, cx: float, cy: float, r: float) -> list[float]:
    n = int(rng.integers(4, 8))
    ang = np.sort(rng.uniform(0.0, 2 * math.pi, n))
    gaps = np.diff(np.append(ang, ang[0] + 2 * math.pi))
    if gaps.max() > math.pi * 0.9:  # keep the centre inside: spread the angles
        ang = np.linspace(0.0, 2 * math.pi, n, endpoint=False) + rng.uniform(0, 1)
    rad = r * rng.uniform(0.6, 1.0, n)
    return [round(v, 2) for a, q in zip(ang, rad, strict=True)
            for v in (cx + q * math.cos(a), cy + q * math.sin(a))]


def random_field(seed: int, rocks: int = 9, puddles: int = 2) -> str:
    """The text of a ``.world`` file (see :mod:`evomotion.studies.quadruped_plan.worlds.world`)."""
    rng = np.random.default_rng(seed)
    start = (0.0, 0.0)
    goal = (WIDTH - 6.0, float(np.round(rng.uniform(-6.0, 6.0), 2)))
    lines = [f"name field{seed}", f"bounds -6 {-HEIGHT / 2:g} {WIDTH:g} {HEIGHT / 2:g}",
             "start 0 0 90", f"goal {goal[0]:g} {goal[1]:g} 0.25"]
    placed = 0
    while placed < rocks + puddles:
        cx, cy = rng.uniform(5.0, WIDTH - 9.0), rng.uniform(-HEIGHT / 2 + 3, HEIGHT / 2 - 3)
        r = rng.uniform(0.8, 2.4)
        if min(math.hypot(cx - start[0], cy - start[1]),
               math.hypot(cx - goal[0], cy - goal[1])) < r + 4.5:
            continue
        if placed < rocks:
            kind = "hidden" if placed == rocks - 1 else "obstacle"
            pts = _star(rng, cx, cy, r)
        else:
            kind = "nostep"
            w, h = rng.uniform(0.8, 2.5), rng.uniform(0.8, 2.5)
            pts = [round(v, 2) for v in (cx, cy, cx + w, cy, cx + w, cy + h, cx, cy + h)]
        lines.append(f"{kind} " + "  ".join(f"{pts[i]:g} {pts[i + 1]:g}"
                                            for i in range(0, len(pts), 2)))
        placed += 1
    return "\n".join(lines) + "\n"
