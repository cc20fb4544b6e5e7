"""ClipUp (Toklu, Liskowski & Srivastava 2020, "ClipUp: A Simple and Powerful Optimizer for
Distribution-based Policy Evolution", PPSN XVI / arXiv:2008.02387, the ClipUp algorithm).

Heavy-ball momentum on the *normalised* gradient, with the velocity's norm clipped to
``max_speed`` (the update is clipped, not the gradient). A pure function over the explicit
velocity array, returning new arrays; used by PGPE for its centre.
"""

from __future__ import annotations

import numpy as np


def clipup_step(x: np.ndarray, grad: np.ndarray, velocity: np.ndarray, *, step_size: float,
                max_speed: float, momentum: float = 0.9) -> tuple[np.ndarray, np.ndarray]:
    """One ClipUp step *ascending* ``grad``: returns ``(x_{k+1}, v_{k+1})`` with
    ``||v_{k+1}|| <= max_speed``. A zero gradient adds nothing to the velocity."""
    norm = float(np.linalg.norm(grad))
    unit = grad / norm if norm > 0.0 else np.zeros_like(grad)
    v = momentum * velocity + step_size * unit  # v' = m v_k + α ∇f / ||∇f||
    speed = float(np.linalg.norm(v))
    if speed > max_speed:  # if ||v'|| > v_max: v' = v_max v' / ||v'||
        v = v * (max_speed / speed)
    return x + v, v  # x_{k+1} = x_k + v_{k+1}
