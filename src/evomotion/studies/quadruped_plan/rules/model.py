"""The 2D quadruped of Ondroušek & Březina (paper 003, section 3.1 and Tab. 1).

A rectangular body ``a x b`` (a = width along the body X axis, b = length along the body Y
axis, the walking axis) with a hip at each corner. Legs, counter-clockwise from the front
left corner (body coordinates, origin at the body centre)::

    leg 0 front-left  (-a/2, +b/2)      leg 3 front-right (+a/2, +b/2)
    leg 1 rear-left   (-a/2, -b/2)      leg 2 rear-right  (+a/2, -b/2)

Each foot lies in an annular sector about its hip: length ``L`` in [l_min, l_max], angle
``beta`` against the body X axis within ``sector_half_width`` of the nominal angle (pi for
the left legs 0, 1; 0 for the right legs 2, 3). The paper's "minimum working angle" is the
front edge of the sector (3/4 pi and 1/4 pi), its "maximum" the rear edge (5/4 pi and
7/4 pi = -1/4 pi), for both sides.

A state is the tuple ``(x, y, phi, p0x, p0y, ..., p3x, p3y)``: the body pose in world
coordinates (phi = angle of the body X axis against the world X axis) and the four feet in
*body* coordinates (all four on the ground). World feet: ``(x, y) + R(phi) p``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

from evomotion.sim.quadruped.geometry import (
    BODY_A,
    BODY_B,
    L_MAX,
    L_MIN,
    LEG_SIDES,
    NOMINAL_ANGLES,
    SECTOR_HALF_WIDTH,
    hip_positions,
)

TWO_PI = 2.0 * math.pi
EPS = 1e-9  # geometric tolerance [units]
WORKSPACE_TOL = 1e-7  # a foot this far outside its sector still counts as inside [units]
STABILITY_TOL = 1e-9  # a margin of -1e-9 counts as 0 (symmetric stances sit on an edge)


@dataclass(frozen=True)
class QuadrupedModel:
    """Body and workspace parameters (the paper's Tab. 1); lengths in the paper's units."""

    a: float = BODY_A
    b: float = BODY_B
    l_min: float = L_MIN
    l_max: float = L_MAX
    sector_half_width: float = SECTOR_HALF_WIDTH  # [rad]
    min_margin: float = 0.0  # least stability margin when a leg is lifted [units]

    def __post_init__(self) -> None:
        if not (0 < self.l_min < self.l_max):
            raise ValueError(f"need 0 < l_min < l_max, got {self.l_min}, {self.l_max}")
        if not (0 < self.sector_half_width < math.pi / 2):
            raise ValueError("sector_half_width must be in (0, pi/2)")
        if self.a <= 0 or self.b <= 0:
            raise ValueError("body sides a, b must be positive")

    # constants of the hot geometry (translation and rotation limits), per leg

    @cached_property
    def _trans(self) -> tuple[tuple[int, float, float, float], ...]:
        """Per leg: (index of the foot's x in a state, hip x, hip y, side)."""
        return tuple((3 + 2 * i, hx, hy, side)
                     for i, ((hx, hy), side) in enumerate(zip(self.hips, self.sides, strict=True)))

    @cached_property
    def _rot(self) -> tuple[tuple[float, float, float, float, tuple[tuple[float, float], ...]],
                            ...]:
        """Per leg: (hip distance, hip angle, outer and inner circle constants, the two wedge
        edges' (angle, offset))."""
        tn = math.tan(self.sector_half_width)
        rot = []
        for (hx, hy), side in zip(self.hips, self.sides, strict=True):
            h = math.hypot(hx, hy)
            wedge = []
            for nx, ny in ((side * tn, -1.0), (side * tn, 1.0)):
                wedge.append((math.atan2(ny, nx), (nx * hx + ny * hy) / math.hypot(nx, ny)))
            rot.append((h, math.atan2(hy, hx), h * h - self.l_max ** 2,
                        h * h - self.l_min ** 2, tuple(wedge)))
        return tuple(rot)

    @cached_property
    def hips(self) -> tuple[tuple[float, float], ...]:
        return hip_positions(self.a, self.b)

    @property
    def sides(self) -> tuple[float, ...]:
        """-1 for the left legs (nominal angle pi), +1 for the right legs (nominal 0)."""
        return LEG_SIDES

    def nominal_angle(self, leg: int) -> float:
        return NOMINAL_ANGLES[leg]

    def min_angle(self, leg: int) -> float:
        """The paper's minimum working angle: the front edge of the sector."""
        hw = self.sector_half_width
        return math.pi - hw if leg < 2 else hw

    def max_angle(self, leg: int) -> float:
        """The paper's maximum working angle: the rear edge of the sector."""
        hw = self.sector_half_width
        return math.pi + hw if leg < 2 else -hw

    def foot_at(self, leg: int, length: float, angle: float) -> tuple[float, float]:
        """Body-frame foot position for leg polar coordinates (L, beta)."""
        hx, hy = self.hips[leg]
        return hx + length * math.cos(angle), hy + length * math.sin(angle)

    def polar(self, leg: int, px: float, py: float) -> tuple[float, float]:
        """(L, beta) of a body-frame foot position, beta within pi of the nominal angle."""
        hx, hy = self.hips[leg]
        rx, ry = px - hx, py - hy
        beta = math.atan2(ry, rx)
        if leg < 2 and beta < 0:
            beta += TWO_PI
        return math.hypot(rx, ry), beta

    def in_workspace(self, leg: int, px: float, py: float, tol: float = WORKSPACE_TOL) -> bool:
        hx, hy = self.hips[leg]
        ux = self.sides[leg] * (px - hx)
        ry = py - hy
        r = math.hypot(ux, ry)
        return (self.l_min - tol <= r <= self.l_max + tol
                and ux * math.tan(self.sector_half_width) >= abs(ry) - tol)

    def nominal_state(self, x: float, y: float, phi: float) -> tuple[float, ...]:
        """Body pose with every leg at mid length and nominal angle."""
        mid = 0.5 * (self.l_min + self.l_max)
        feet: list[float] = []
        for leg in range(4):
            feet.extend(self.foot_at(leg, mid, self.nominal_angle(leg)))
        return (x, y, phi, *feet)


def world_feet(state: tuple[float, ...]) -> list[tuple[float, float]]:
    x, y, phi = state[0], state[1], state[2]
    c, s = math.cos(phi), math.sin(phi)
    return [(x + c * state[3 + 2 * i] - s * state[4 + 2 * i],
             y + s * state[3 + 2 * i] + c * state[4 + 2 * i]) for i in range(4)]


def triangle_margin(ax: float, ay: float, bx: float, by: float, cx: float, cy: float,
                    px: float = 0.0, py: float = 0.0) -> float:
    """Signed distance of (px, py) to the nearest edge of triangle abc (> 0 inside)."""
    orient = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    if abs(orient) < 1e-12:
        return -math.inf  # degenerate support
    sgn = 1.0 if orient > 0 else -1.0
    m = math.inf
    for (ux, uy, vx, vy) in ((ax, ay, bx, by), (bx, by, cx, cy), (cx, cy, ax, ay)):
        ex, ey = vx - ux, vy - uy
        d = sgn * (ex * (py - uy) - ey * (px - ux)) / math.hypot(ex, ey)
        m = min(m, d)
    return m


def lift_margin(state: tuple[float, ...], leg: int) -> float:
    """Stability margin with ``leg`` lifted: the body centre against the other three feet."""
    pts = [(state[3 + 2 * i], state[4 + 2 * i]) for i in range(4) if i != leg]
    return triangle_margin(*pts[0], *pts[1], *pts[2])


def support_margin(state: tuple[float, ...]) -> float:
    """Signed distance of the body centre to the convex hull of the four feet (> 0 inside)."""
    pts = [(state[3 + 2 * i], state[4 + 2 * i]) for i in range(4)]
    best = -math.inf
    m = math.inf
    for i in range(4):
        for j in range(i + 1, 4):
            (ux, uy), (vx, vy) = pts[i], pts[j]
            ex, ey = vx - ux, vy - uy
            n = math.hypot(ex, ey)
            if n < 1e-12:
                continue
            others = [(ex * (qy - uy) - ey * (qx - ux)) for k, (qx, qy) in enumerate(pts)
                      if k not in (i, j)]
            if all(o >= -1e-12 for o in others) or all(o <= 1e-12 for o in others):
                sgn = 1.0 if sum(others) >= 0 else -1.0
                m = min(m, sgn * (ex * (0.0 - uy) - ey * (0.0 - ux)) / n)
                best = m
    return best


def translation_limit(model: QuadrupedModel, state: tuple[float, ...], sign: float) -> float:
    """Largest body shift ``t >= 0`` along ``sign`` * body Y keeping every foot in its sector.

    The feet move by ``-sign * t`` in body coordinates along a straight line; the limit is
    the first exit from the wedge, the outer circle, or entry into the inner circle.
    """
    cot = 1.0 / math.tan(model.sector_half_width)
    lmax2, lmin, sqrt = model.l_max ** 2, model.l_min, math.sqrt
    best = math.inf
    for j, hx, hy, side in model._trans:
        ux = side * (state[j] - hx)
        ry = sign * (state[j + 1] - hy)
        t = ry + ux * cot  # the wedge edge
        r = lmax2 - ux * ux
        u = ry + sqrt(r) if r > 0 else ry  # the outer circle
        if u < t:
            t = u
        # the inner circle blocks the way down only from above it (a foot on the circle's
        # vertical tangent, ux = l_min, slides past it; so does one that would dip into it by
        # no more than the workspace tolerance, as in_workspace accepts)
        if ux < lmin - WORKSPACE_TOL and ry > 0:
            u = ry - sqrt(lmin * lmin - ux * ux)
            if u < t:
                t = u
        if t < best:
            best = t
    return best if best > 0.0 else 0.0


def rotation_limit(model: QuadrupedModel, state: tuple[float, ...], direction: float) -> float:
    """Largest body rotation [rad] about its centre in ``direction`` (+1 = counter-clockwise)
    keeping every foot inside its sector along the whole arc (the feet turn by -angle in body
    coordinates, on circles about the body centre). Each boundary (outer and inner circle,
    the two wedge edges) is an arc condition cos(theta - c) >= k or <= k on that circle."""
    move = -direction
    best = math.inf
    pi, acos, atan2, sqrt = math.pi, math.acos, math.atan2, math.sqrt
    for i, (h, th, out_c, in_c, wedge) in enumerate(model._rot):
        px, py = state[3 + 2 * i], state[4 + 2 * i]
        r2 = px * px + py * py
        if r2 < EPS * EPS:
            return 0.0
        r = sqrt(r2)
        theta = atan2(py, px)
        # keep inside the outer circle: an arc about the hip direction
        k = (r2 + out_c) / (2 * r * h)
        if k > -1.0:
            v = acos(k if k < 1.0 else 1.0) - move * ((theta - th + pi) % TWO_PI - pi)
            if v < best:
                best = v
        # keep outside the inner circle: the forbidden arc lies ahead or behind
        k = (r2 + in_c) / (2 * r * h)
        if k < 1.0:
            v = TWO_PI - acos(k if k > -1.0 else -1.0) - (move * (theta - th)) % TWO_PI
            if v < best:
                best = v
        # keep on the inner side of both wedge edges
        for centre, nh in wedge:
            k = nh / r
            if k > -1.0:
                v = acos(k if k < 1.0 else 1.0) - move * ((theta - centre + pi) % TWO_PI - pi)
                if v < best:
                    best = v
        if best <= 0.0:
            return 0.0
    return best
