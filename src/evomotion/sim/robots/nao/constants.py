"""NAO H25 facts shared by every NAO study: joint names, the initial pose, lengths, masses and
the fall thresholds. Angles are radians, lengths metres, masses kilograms (SI throughout).

Sources: Aldebaran's published NAO H25 V5 tables (joint names and ranges, "H25 – Links – V3.3"
link lengths, the V5 masses table), gathered in ``/work/shared/reference/nao-h25.md`` and cited
per value in ``evomotion/sim/robots/nao/README.md``; the initial pose is the walk-ready crouch with
which Webots' NAO motions start; the sole box is the one of B-Human ``RobotDimensions.h``.
"""

from __future__ import annotations

import numpy as np

from evomotion.sim import state

#: The 22 servos of the model, in actuator order of the MJCF (Aldebaran's and Webots' names).
JOINTS: tuple[str, ...] = (
    "HeadYaw", "HeadPitch",
    "LShoulderPitch", "LShoulderRoll", "LElbowYaw", "LElbowRoll",
    "LHipYawPitch", "LHipRoll", "LHipPitch", "LKneePitch", "LAnklePitch", "LAnkleRoll",
    "RHipYawPitch", "RHipRoll", "RHipPitch", "RKneePitch", "RAnklePitch", "RAnkleRoll",
    "RShoulderPitch", "RShoulderRoll", "RElbowYaw", "RElbowRoll",
)

#: The 10 leg servos the humanoid-step GA drives (paper 000 section 1.2, order of its Table 1).
LEG_SERVOS: tuple[str, ...] = (
    "RHipPitch", "RHipRoll", "RKneePitch", "RAnklePitch", "RAnkleRoll",
    "LHipPitch", "LHipRoll", "LKneePitch", "LAnklePitch", "LAnkleRoll",
)

#: The six joints of each leg from hip to foot, the order of :mod:`evomotion.sim.robots.nao.leg_ik`.
LEFT_LEG: tuple[str, ...] = ("LHipYawPitch", "LHipRoll", "LHipPitch", "LKneePitch",
                             "LAnklePitch", "LAnkleRoll")
RIGHT_LEG: tuple[str, ...] = ("RHipYawPitch", "RHipRoll", "RHipPitch", "RKneePitch",
                              "RAnklePitch", "RAnkleRoll")

#: Initial pose: the Webots NAO walk-ready crouch with which all of Webots' NAO motions start
#: (HipPitch -0.523, KneePitch 1.047, AnklePitch -0.523 keep the torso upright and soles flat;
#: arms down at the sides). Joints not listed are 0.
INITIAL_POSE: dict[str, float] = {
    "LShoulderPitch": 1.745, "LShoulderRoll": 0.349, "LElbowYaw": -1.396, "LElbowRoll": -1.396,
    "RShoulderPitch": 1.745, "RShoulderRoll": -0.349, "RElbowYaw": 1.396, "RElbowRoll": 1.396,
    "LHipPitch": -0.523, "LKneePitch": 1.047, "LAnklePitch": -0.523,
    "RHipPitch": -0.523, "RKneePitch": 1.047, "RAnklePitch": -0.523,
}

#: Published leg lengths (m): hip offset Y and Z (torso origin to hip joint), thigh, tibia,
#: foot height (ankle to sole, V3.3+).
HIP_OFFSET_Y_M, HIP_OFFSET_Z_M = 0.050, 0.085
THIGH_M, TIBIA_M, FOOT_HEIGHT_M = 0.100, 0.1029, 0.04519
#: Published total mass of the V5 table (kg).
TOTAL_MASS_KG = 5.3054
#: Half length and half width of the sole collision box of the MJCF (m).
SOLE_HALF_M: tuple[float, float] = (0.08, 0.0444)

#: Fallen: the torso origin below this height (the crouch stands at about 0.305 m) ...
FALL_HEIGHT_M = 0.20
#: ... or the torso's up axis tilted more than this from the vertical (45 degrees).
FALL_TILT_RAD = np.pi / 4

#: Name of the torso's free joint (the first joint: ``qpos[0:7]`` = torso position, quaternion).
ROOT_JOINT = "root"
#: The physics state recorded by rollouts and its qpos offset (any robot's: sim/state.py).
STATE_SPEC = state.STATE_SPEC
STATE_QPOS_OFFSET = state.QPOS_OFFSET
