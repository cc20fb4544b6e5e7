"""The NAO H25 robot in one folder: MJCF (``nao_h25.xml``, sources in ``README.md``), spec
(``nao.toml``), constants, leg kinematics, Webots motions, replay, NAOqi exports.

The spec declares this folder's code as the NAO's capabilities (``leg_ik``, ``speed_limits``,
``webots_names``, ``naoqi_export``, ``naoqi_policy``; :mod:`evomotion.sim.robots`).

- :mod:`.constants`: joint names, initial pose, leg lengths, masses, fall thresholds (SI);
- :mod:`.model`: loading the MJCF, initial pose/state, ``qpos``/``qvel`` addresses by name;
- :mod:`.scene`: scenes built on the NAO MJCF (extra bodies and sensors), sensor slices;
- :mod:`.leg_ik`: closed-form leg inverse/forward kinematics;
- :mod:`.joint_limits`: the motors' no-load speeds, motions checked against them;
- :mod:`.replay`: open-loop replay of a ``.motion`` (``evomotion replay``);
- :mod:`.export`: motions exported to NAOqi; ``motions/``: Webots' NAO motions (Apache-2.0);
- :mod:`.policy_export`: closed-loop policies exported to NAOqi (``naoqi/``), run by
  :mod:`.policy_runner` (a standard-library script for the robot's Python 2.7 or Python 3).

The constants and the model functions are re-exported here (``from evomotion.sim.robots
import nao; nao.load_model()``); the other modules are imported by name.
"""

from evomotion.sim.robots.nao.constants import (
    FALL_HEIGHT_M,
    FALL_TILT_RAD,
    FOOT_HEIGHT_M,
    HIP_OFFSET_Y_M,
    HIP_OFFSET_Z_M,
    INITIAL_POSE,
    JOINTS,
    LEFT_LEG,
    LEG_SERVOS,
    RIGHT_LEG,
    ROOT_JOINT,
    SOLE_HALF_M,
    STATE_QPOS_OFFSET,
    STATE_SPEC,
    THIGH_M,
    TIBIA_M,
    TOTAL_MASS_KG,
)
from evomotion.sim.robots.nao.model import (
    MODEL_PATH,
    get_state,
    initial_data,
    initial_state,
    joint_columns,
    joint_ranges,
    load_model,
    model_xml,
    pose_vector,
    qpos_address,
    qvel_address,
    state_qpos,
    state_qpos_all,
    state_qvel,
)


def is_nao(robot: str) -> bool:
    """Does a config's ``problem.robot`` name the bundled NAO (the default "" or ``nao``)? A
    copy of ``nao.toml`` under another path is another robot (it has none of this folder's
    code). Studies ask a robot for a capability instead (:meth:`Robot.has`)."""
    return robot in ("", "nao")


__all__ = [
    "FALL_HEIGHT_M", "FALL_TILT_RAD", "FOOT_HEIGHT_M", "HIP_OFFSET_Y_M", "HIP_OFFSET_Z_M",
    "INITIAL_POSE", "JOINTS", "LEFT_LEG", "LEG_SERVOS", "MODEL_PATH", "RIGHT_LEG", "ROOT_JOINT",
    "SOLE_HALF_M", "STATE_QPOS_OFFSET", "STATE_SPEC", "THIGH_M", "TIBIA_M", "TOTAL_MASS_KG",
    "get_state", "initial_data", "initial_state", "is_nao", "joint_columns", "joint_ranges",
    "load_model", "model_xml", "pose_vector", "qpos_address", "qvel_address", "state_qpos",
    "state_qpos_all", "state_qvel",
]
