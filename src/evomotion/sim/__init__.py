"""MuJoCo simulation: the NAO H25 model, batched rollouts and offscreen rendering.

``MUJOCO_GL`` must be chosen before :mod:`mujoco` is first imported; we default to OSMesa
(CPU, headless) unless the user already set a backend (``egl`` on GPU machines).
"""

import os

os.environ.setdefault("MUJOCO_GL", "osmesa")
