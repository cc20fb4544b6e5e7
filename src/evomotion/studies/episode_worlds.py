"""Episode worlds of a closed-loop policy search, one per episode seed (shared by the studies
that evolve policies: humanoid-balance, humanoid-walk).

An episode's world comes from ``numpy.random.default_rng(seed)`` alone (:func:`episode_world`):
with ``perturb`` the friction, link masses, torso CoM, motor strength and servo latency of
:func:`evomotion.sim.worlds.draw_worlds` (the default ranges of
:class:`~evomotion.sim.worlds.Perturbation`), then one push: magnitude ``U(push_min,
push_max)`` N s (scaled by the robot's mass over the NAO's,
:meth:`~evomotion.sim.worlds.Perturbation.for_mass`), direction uniform on the horizontal
circle, time ``U(push_window) x duration_s``. The same seed gives the same world whatever else
is evaluated beside it, so any split of the rows over evaluators gives the same numbers.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from evomotion.sim.worlds import Perturbation, World, draw_worlds


@dataclass(frozen=True)
class WorldDraw:
    """What :func:`episode_world` draws from: push range (N s, already scaled for the robot's
    mass), push time window (fractions of ``duration_s``), whether to perturb the model."""

    push_ns: tuple[float, float]
    push_window: tuple[float, float]
    duration_s: float
    perturb: bool = True


def push_range(robot, push_min_ns: float, push_max_ns: float) -> tuple[float, float]:
    """The push magnitudes for ``robot`` (N s): the NAO's range scaled by its mass."""
    lo, hi = Perturbation(push_ns=(push_min_ns, push_max_ns)).for_mass(robot.mass_kg).push_ns
    return float(lo), float(hi)


def episode_world(model, draw: WorldDraw, seed: int, push_ns: float | None = None) -> World:
    """The world of episode ``seed`` (see the module doc); ``push_ns`` fixes the magnitude
    (direction and time still drawn, so the worlds match those of the same seeds otherwise)."""
    rng = np.random.default_rng(int(seed))
    world = (draw_worlds(model, Perturbation(), 1, rng, draw.duration_s)[0] if draw.perturb
             else World(model))
    mag = float(rng.uniform(*draw.push_ns))
    angle = float(rng.uniform(0.0, 2.0 * math.pi))
    when = float(rng.uniform(*draw.push_window)) * draw.duration_s
    if push_ns is not None:
        mag = float(push_ns)
    vec = (mag * math.cos(angle), mag * math.sin(angle), 0.0)
    params = dict(world.params, push_ns=list(vec), push_time_s=when, push_magnitude_ns=mag)
    return dataclasses.replace(world, push_ns=vec, push_time_s=when, params=params)
