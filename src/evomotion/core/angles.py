"""Angles wrapped into one turn (rad): the one helper the simulators and studies share (there
were five copies)."""

from __future__ import annotations

from typing import Any

import numpy as np


def wrap_angle(a: Any) -> Any:
    """``a`` (rad) wrapped into [-pi, pi): a float for a number, an array for an array."""
    w = (np.asarray(a, dtype=float) + np.pi) % (2 * np.pi) - np.pi
    return float(w) if w.ndim == 0 else w


def wrap_angle_upper(a: Any) -> Any:
    """``a`` (rad) wrapped into (-pi, pi] (pi stays pi): a float or an array."""
    w = -((-np.asarray(a, dtype=float) + np.pi) % (2 * np.pi) - np.pi)
    return float(w) if w.ndim == 0 else w
