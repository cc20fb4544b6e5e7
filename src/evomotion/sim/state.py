"""The physics state rollouts record, for any robot: its layout read from the model.

Every simulator records ``mjSTATE_FULLPHYSICS`` states (:data:`STATE_SPEC`, MuJoCo API
reference, ``mj_getState``): the time, then ``qpos[nq]``, ``qvel[nv]``, ``act[na]``, ... So
``qpos[i]`` of a recorded state is at ``QPOS_OFFSET + i`` and ``qvel[j]`` at ``QPOS_OFFSET +
nq + j``; a joint's addresses come from the model (``jnt_qposadr``, ``jnt_dofadr``). Without a
joint name the accessors read the model's first joint: the free joint of the torso of every
robot of :mod:`evomotion.sim.robots` (x, y, z, qw, qx, qy, qz; vx, vy, vz, wx, wy, wz).
"""

from __future__ import annotations

import mujoco
import numpy as np

#: The physics state recorded by rollouts: time, qpos, qvel, act, ... (``mj_getState``).
STATE_SPEC = mujoco.mjtState.mjSTATE_FULLPHYSICS
#: Index of ``qpos[0]`` in a ``STATE_SPEC`` state vector: after the time (``mjSTATE_TIME``).
QPOS_OFFSET = 1


def state_size(model: mujoco.MjModel) -> int:
    """Length of a ``STATE_SPEC`` state vector of ``model``."""
    return int(mujoco.mj_stateSize(model, STATE_SPEC))


def get_state(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    """The ``STATE_SPEC`` state vector of ``data``."""
    state = np.empty(state_size(model))
    mujoco.mj_getState(model, data, state, STATE_SPEC)
    return state


def _joint_id(model: mujoco.MjModel, joint: str | None) -> int:
    return 0 if joint is None else int(model.joint(joint).id)


def qpos_address(model: mujoco.MjModel, joint: str | None = None) -> int:
    """Index of ``joint``'s first ``qpos`` value (default: the model's first joint)."""
    return int(model.jnt_qposadr[_joint_id(model, joint)])


def qvel_address(model: mujoco.MjModel, joint: str | None = None) -> int:
    """Index of ``joint``'s first ``qvel`` value (default: the model's first joint)."""
    return int(model.jnt_dofadr[_joint_id(model, joint)])


def state_qpos(model: mujoco.MjModel, states: np.ndarray, joint: str | None = None,
               n: int = 1) -> np.ndarray:
    """``n`` ``qpos`` values of ``joint`` from recorded states ``[..., nstate]`` (a view)."""
    i = QPOS_OFFSET + qpos_address(model, joint)
    return states[..., i:i + n]


def state_qvel(model: mujoco.MjModel, states: np.ndarray, joint: str | None = None,
               n: int = 1) -> np.ndarray:
    """``n`` ``qvel`` values of ``joint`` from recorded states (a view)."""
    i = QPOS_OFFSET + model.nq + qvel_address(model, joint)
    return states[..., i:i + n]


def state_qpos_all(model: mujoco.MjModel, states: np.ndarray) -> np.ndarray:
    """The whole ``qpos[..., nq]`` of recorded states (a view)."""
    return states[..., QPOS_OFFSET:QPOS_OFFSET + model.nq]
