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
