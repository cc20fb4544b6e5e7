"""MuJoCo simulation: the NAO H25 model, batched rollouts and offscreen rendering.

``MUJOCO_GL`` must be chosen before :mod:`mujoco` is first imported. Unless the user set it,
we pick OSMesa (CPU, headless) when ``libOSMesa`` exists, else EGL when ``libEGL`` exists,
else ``disable``: physics still works and only rendering reports that no backend exists
(importing mujoco with a backend whose library is missing would fail outright).
"""

import ctypes.util
import os

if "MUJOCO_GL" not in os.environ:
    if ctypes.util.find_library("OSMesa"):
        os.environ["MUJOCO_GL"] = "osmesa"
    elif ctypes.util.find_library("EGL"):
        os.environ["MUJOCO_GL"] = "egl"
    else:
        os.environ["MUJOCO_GL"] = "disable"

import logging  # noqa: E402

import mujoco  # noqa: E402

_log = logging.getLogger("evomotion.mujoco")


def _mujoco_warning(message: str) -> None:
    """MuJoCo's warnings go to the ``evomotion.mujoco`` logger, not to ``MUJOCO_LOG.TXT`` in
    the current folder (nothing is written outside the run folder or a path the user names)."""
    _log.warning("MuJoCo: %s", " ".join(str(message).split()))


mujoco.set_mju_user_warning(_mujoco_warning)
