"""Webots' own NAO motions that the studies need, shipped as package data in ``motions/``
(Webots is Apache-2.0, Copyright Cyberbotics Ltd.; see ``motions/NOTICE.txt``), read with
:func:`shipped_motion` through :mod:`importlib.resources`."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from evomotion.sim.motion import Motion, parse_motion

#: The Webots motions shipped in ``motions/`` (package data).
SHIPPED_MOTIONS: tuple[str, ...] = ("Shoot", "SideStepLeft", "SideStepRight", "TurnLeft40",
                                     "TurnLeft60", "TurnRight40")


def shipped_motion(name: str) -> Motion:
    """A Webots NAO motion shipped with evomotion (``name`` in :data:`SHIPPED_MOTIONS`)."""
    if name not in SHIPPED_MOTIONS:
        raise ValueError(f"no shipped motion {name!r}; available: {', '.join(SHIPPED_MOTIONS)}")
    res = resources.files(__package__).joinpath("motions", f"{name}.motion")
    return parse_motion(res.read_text(encoding="utf-8-sig"), Path(str(res)))
