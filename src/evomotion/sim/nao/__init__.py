"""The NAO H25 robot in one place: model, constants, leg kinematics, Webots motions, replay.

- :mod:`.constants`: joint names, initial pose, leg lengths, masses, fall thresholds (SI);
- :mod:`.model`: loading the MJCF, initial pose/state, ``qpos``/``qvel`` addresses by name;
- :mod:`.scene`: scenes built on the NAO MJCF (extra bodies and sensors), sensor slices;
- :mod:`.leg_ik`: closed-form leg inverse/forward kinematics;
- :mod:`.motion`: the Webots ``.motion`` reader/writer and the motions shipped as package data;
- :mod:`.replay`: open-loop replay of a ``.motion`` (``evomotion replay``).

The constants and the model functions are re-exported here (``from evomotion.sim import nao;
nao.load_model()``); the other modules are imported by name.
"""

from evomotion.sim.nao.constants import (
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
from evomotion.sim.nao.model import (
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

__all__ = [
    "FALL_HEIGHT_M", "FALL_TILT_RAD", "FOOT_HEIGHT_M", "HIP_OFFSET_Y_M", "HIP_OFFSET_Z_M",
    "INITIAL_POSE", "JOINTS", "LEFT_LEG", "LEG_SERVOS", "MODEL_PATH", "RIGHT_LEG", "ROOT_JOINT",
    "SOLE_HALF_M", "STATE_QPOS_OFFSET", "STATE_SPEC", "THIGH_M", "TIBIA_M", "TOTAL_MASS_KG",
    "get_state", "initial_data", "initial_state", "joint_columns", "joint_ranges", "load_model",
    "model_xml", "pose_vector", "qpos_address", "qvel_address", "state_qpos", "state_qpos_all",
    "state_qvel",
]
