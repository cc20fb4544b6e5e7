"""The NAO H25 model: loading, joint tables and the initial pose.

The MJCF in ``models/nao_h25.xml`` is authored from Aldebaran's published NAO H25 V5 tables
(link lengths, joint ranges, masses, CoMs, inertias; sources in ``models/README.md``).
Angles are radians, lengths metres. Joint names are Aldebaran's (and Webots').
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import mujoco
import numpy as np

MODEL_PATH = Path(__file__).with_name("models") / "nao_h25.xml"

#: The 22 servos of the seed, in actuator order of the MJCF.
JOINTS: tuple[str, ...] = (
    "HeadYaw", "HeadPitch",
    "LShoulderPitch", "LShoulderRoll", "LElbowYaw", "LElbowRoll",
    "LHipYawPitch", "LHipRoll", "LHipPitch", "LKneePitch", "LAnklePitch", "LAnkleRoll",
    "RHipYawPitch", "RHipRoll", "RHipPitch", "RKneePitch", "RAnklePitch", "RAnkleRoll",
    "RShoulderPitch", "RShoulderRoll", "RElbowYaw", "RElbowRoll",
)

#: The 10 leg servos the seed's GA drives (seed section 1.2, order of its Table 1 pairs).
LEG_SERVOS: tuple[str, ...] = (
    "RHipPitch", "RHipRoll", "RKneePitch", "RAnklePitch", "RAnkleRoll",
    "LHipPitch", "LHipRoll", "LKneePitch", "LAnklePitch", "LAnkleRoll",
)

#: Initial pose: the Webots NAO walk-ready crouch with which all of Webots' NAO motions start
#: (HipPitch -0.523, KneePitch 1.047, AnklePitch -0.523 keep the torso upright and soles flat;
#: arms down at the sides). Joints not listed are 0.
INITIAL_POSE: dict[str, float] = {
    "LShoulderPitch": 1.745, "LShoulderRoll": 0.349, "LElbowYaw": -1.396, "LElbowRoll": -1.396,
    "RShoulderPitch": 1.745, "RShoulderRoll": -0.349, "RElbowYaw": 1.396, "RElbowRoll": 1.396,
    "LHipPitch": -0.523, "LKneePitch": 1.047, "LAnklePitch": -0.523,
    "RHipPitch": -0.523, "RKneePitch": 1.047, "RAnklePitch": -0.523,
}

#: Published leg lengths (m): hip offset Z, thigh, tibia, foot height (V3.3+).
HIP_OFFSET_Z_M, THIGH_M, TIBIA_M, FOOT_HEIGHT_M = 0.085, 0.100, 0.1029, 0.04519
#: Published total mass of the V5 table (kg).
TOTAL_MASS_KG = 5.3054

STATE_SPEC = mujoco.mjtState.mjSTATE_FULLPHYSICS


@lru_cache(maxsize=1)
def _model_xml() -> str:
    return MODEL_PATH.read_text()


def load_model() -> mujoco.MjModel:
    """A fresh :class:`mujoco.MjModel` of the NAO on a flat floor."""
    return mujoco.MjModel.from_xml_string(_model_xml())


def joint_ranges(model: mujoco.MjModel, names: tuple[str, ...] = JOINTS) -> np.ndarray:
    """``[len(names), 2]`` joint ranges (rad) from the model."""
    return np.array([model.joint(n).range for n in names], dtype=float)


def pose_vector(pose: dict[str, float] | None = None) -> np.ndarray:
    """Targets for the 22 actuators (``JOINTS`` order); missing joints from ``INITIAL_POSE``."""
    full = {**INITIAL_POSE, **(pose or {})}
    return np.array([full.get(n, 0.0) for n in JOINTS], dtype=float)


def initial_data(model: mujoco.MjModel, pose: np.ndarray | None = None,
                 clearance_m: float = 0.0005) -> mujoco.MjData:
    """MjData with the joints at ``pose`` (22 values) and the lower sole ``clearance_m`` above
    the floor, torso upright facing +x, at rest, with the actuators holding the pose."""
    q = pose_vector() if pose is None else np.asarray(pose, dtype=float)
    data = mujoco.MjData(model)
    for name, value in zip(JOINTS, q, strict=True):
        data.joint(name).qpos = value
    data.ctrl[:] = q
    mujoco.mj_kinematics(model, data)
    soles = [data.site("l_sole_site").xpos[2], data.site("r_sole_site").xpos[2]]
    data.qpos[2] += clearance_m - min(soles)
    mujoco.mj_forward(model, data)
    return data


def initial_state(model: mujoco.MjModel, pose: np.ndarray | None = None) -> np.ndarray:
    """Full physics state vector (``mjSTATE_FULLPHYSICS``) of :func:`initial_data`."""
    data = initial_data(model, pose)
    state = np.empty(mujoco.mj_stateSize(model, STATE_SPEC))
    mujoco.mj_getState(model, data, state, STATE_SPEC)
    return state
