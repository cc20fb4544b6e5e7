"""The NAO H25 MuJoCo model: loading, the initial pose and state, named state accessors.

The MJCF ``evomotion/sim/robots/nao/nao_h25.xml`` is authored from Aldebaran's published NAO H25
V5 tables (link lengths, joint ranges, masses, CoMs, inertias; sources in
``sim/robots/nao/README.md``). Scenes that add bodies or sensors start from :func:`model_xml`
(see :mod:`evomotion.sim.robots.nao.scene`).
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import mujoco
import numpy as np

from evomotion.sim import state
from evomotion.sim.robots.nao.constants import INITIAL_POSE, JOINTS, ROOT_JOINT

MODEL_PATH = Path(__file__).resolve().parent / "nao_h25.xml"
MAX_CLEARANCE_M = 0.1  # the highest start above the floor (m), as a robot spec's clearance_m


@lru_cache(maxsize=1)
def model_xml() -> str:
    """The MJCF text of the NAO on a flat floor (the package's file, read bounded)."""
    from evomotion.textio import decode_utf8, read_file_bytes

    return decode_utf8(read_file_bytes(MODEL_PATH, "NAO model", 4 * 2**20), MODEL_PATH)


def load_model() -> mujoco.MjModel:
    """A fresh :class:`mujoco.MjModel` of the NAO on a flat floor."""
    return mujoco.MjModel.from_xml_string(model_xml())


def joint_ranges(model: mujoco.MjModel, names: tuple[str, ...] = JOINTS) -> np.ndarray:
    """``[len(names), 2]`` joint ranges (rad) from the model."""
    return np.array([model.joint(n).range for n in names], dtype=float)


def joint_columns(names: tuple[str, ...]) -> list[int]:
    """Columns of ``names`` in a 22-actuator vector (``JOINTS`` order)."""
    return [JOINTS.index(n) for n in names]


def pose_vector(pose: dict[str, float] | None = None) -> np.ndarray:
    """Targets for the 22 actuators (``JOINTS`` order); missing joints from ``INITIAL_POSE``."""
    full = {**INITIAL_POSE, **(pose or {})}
    return np.array([full.get(n, 0.0) for n in JOINTS], dtype=float)


def qpos_address(model: mujoco.MjModel, joint: str = ROOT_JOINT) -> int:
    """Index of ``joint``'s first ``qpos`` value (free joints: x, y, z, qw, qx, qy, qz)."""
    return state.qpos_address(model, joint)


def qvel_address(model: mujoco.MjModel, joint: str = ROOT_JOINT) -> int:
    """Index of ``joint``'s first ``qvel`` value (free joints: vx, vy, vz, wx, wy, wz)."""
    return state.qvel_address(model, joint)


def state_qpos(model: mujoco.MjModel, states: np.ndarray, joint: str = ROOT_JOINT,
               n: int = 1) -> np.ndarray:
    """``n`` ``qpos`` values of ``joint`` from recorded states (:mod:`evomotion.sim.state`)."""
    return state.state_qpos(model, states, joint, n)


def state_qvel(model: mujoco.MjModel, states: np.ndarray, joint: str = ROOT_JOINT,
               n: int = 1) -> np.ndarray:
    """``n`` ``qvel`` values of ``joint`` from recorded states (:mod:`evomotion.sim.state`)."""
    return state.state_qvel(model, states, joint, n)


state_qpos_all = state.state_qpos_all
get_state = state.get_state


def initial_data(model: mujoco.MjModel, pose: np.ndarray | None = None,
                 clearance_m: float = 0.0005) -> mujoco.MjData:
    """MjData with the joints at ``pose`` (22 values) and the lower sole ``clearance_m`` above
    the floor, torso upright facing +x, at rest, with the actuators holding the pose.
    ``clearance_m`` must be finite, 0 to 0.1 m (one :class:`InputError` line otherwise)."""
    from evomotion.core.checks import check_number

    check_number("clearance_m", clearance_m, lo=0.0, hi=MAX_CLEARANCE_M)
    q = pose_vector() if pose is None else np.asarray(pose, dtype=float)
    data = mujoco.MjData(model)
    for name, value in zip(JOINTS, q, strict=True):
        data.joint(name).qpos = value
    data.ctrl[:] = q
    mujoco.mj_kinematics(model, data)
    soles = [data.site("l_sole_site").xpos[2], data.site("r_sole_site").xpos[2]]
    data.qpos[qpos_address(model) + 2] += clearance_m - min(soles)  # torso z
    mujoco.mj_forward(model, data)
    return data


def initial_state(model: mujoco.MjModel, pose: np.ndarray | None = None) -> np.ndarray:
    """Full physics state vector (``mjSTATE_FULLPHYSICS``) of :func:`initial_data`."""
    return get_state(model, initial_data(model, pose))
