"""The NAO's left-right mirror: the joint targets that play a motion in mirror image about the
torso's sagittal (x-z) plane.

The model's kinematics and masses are symmetric (``tests/sim/robots/nao/test_mirror.py``
checks every body's position under random poses to 1e-12 m; the joint ranges of the knee and
ankle pitch differ between the sides by about 0.01 rad, the ankle roll's by 0.0002 rad): each
``L*`` joint's mirror is its ``R*`` partner with the same angle for pitch joints (a common y
axis) and for the hip yaw-pitch (whose two axes are already mirror images), and the opposite
angle for roll and yaw joints (x and z axes). A right-foot kick mirrored this way is the same
kick with the left foot.
"""

from __future__ import annotations

import numpy as np

from evomotion.sim.robots.nao.constants import JOINTS


def _partner(joint: str) -> str:
    side = {"L": "R", "R": "L"}.get(joint[0])
    return side + joint[1:] if side and joint[1].isupper() else joint


def _sign(joint: str) -> float:
    return -1.0 if ("Roll" in joint or "Yaw" in joint) and "YawPitch" not in joint else 1.0


def joint_mirror(joint: str) -> tuple[str, float]:
    """The joint ``joint`` of the mirror image and the sign of its angle there (the robot's
    ``mirror`` capability: symmetric policies, :mod:`evomotion.core.policies.mirror`)."""
    return _partner(joint), _sign(joint)


#: column ``i`` of a mirrored pose is column ``MIRROR_COLUMNS[i]`` of the pose times
#: ``MIRROR_SIGNS[i]`` (order :data:`JOINTS`)
MIRROR_COLUMNS = np.array([JOINTS.index(_partner(j)) for j in JOINTS])
MIRROR_SIGNS = np.array([_sign(j) for j in JOINTS])


def mirror_targets(q: np.ndarray) -> np.ndarray:
    """Joint targets ``q[..., 22]`` (order :data:`JOINTS`, rad) played in mirror image."""
    return np.asarray(q, dtype=float)[..., MIRROR_COLUMNS] * MIRROR_SIGNS
