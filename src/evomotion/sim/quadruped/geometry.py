"""The paper-003 quadruped's body geometry, defined once (Ondroušek & Březina, section 3.1,
Tab. 1), in paper units.

A rectangular body ``a x b`` (``a`` along body X, ``b`` along body Y, the walking axis) with
a hip at each corner, legs counter-clockwise from the front left: leg 0 front-left
(-a/2, +b/2), 1 rear-left (-a/2, -b/2), 2 rear-right (+a/2, -b/2), 3 front-right
(+a/2, +b/2). Each foot lies in an annular sector about its hip: hip-foot distance in
[``L_MIN``, ``L_MAX``], angle within ``SECTOR_HALF_WIDTH`` of the leg's nominal angle (pi for
the left legs 0, 1; 0 for the right legs 2, 3).

The robot owns its body, so the numbers live here, on the robot side: the MuJoCo model
(:mod:`.model`, :class:`~.model.QuadrupedSpec`) and the planning study's rules model
(``studies/quadruped_plan/rules/model.py``, a layer above, which may import this) both take
their defaults and hip layout from this module; the compiled successors (``_walkcore.c``)
get every number passed in from the rules model.
"""

from __future__ import annotations

import math

BODY_A = 2.5  # body side along body X [paper units] (Tab. 1)
BODY_B = 3.0  # body side along body Y, the walking axis [paper units] (Tab. 1)
L_MIN = 1.0  # least hip-foot distance [paper units] (Tab. 1)
L_MAX = 2.0  # greatest hip-foot distance [paper units] (Tab. 1)
SECTOR_HALF_WIDTH = math.pi / 4  # [rad] half the sector's angle about the nominal angle
NOMINAL_ANGLES = (math.pi, math.pi, 0.0, 0.0)  # [rad] sector centres against body X, per leg
LEG_SIDES = (-1.0, -1.0, 1.0, 1.0)  # -1 for the left legs (nominal pi), +1 for the right


def hip_positions(a: float, b: float) -> tuple[tuple[float, float], ...]:
    """The four hips ``(x, y)`` in body coordinates (origin at the body centre), legs 0-3."""
    a2, b2 = a / 2, b / 2
    return ((-a2, b2), (-a2, -b2), (a2, -b2), (a2, b2))
