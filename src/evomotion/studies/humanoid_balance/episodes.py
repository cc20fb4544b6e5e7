"""Balance episodes: one perturbed world per episode seed, a pushed robot under a batched policy.

An episode's world comes from ``numpy.random.default_rng(seed)`` alone (:func:`episode_world`):
with ``perturb`` the friction, link masses, torso CoM, motor strength and servo latency of
:func:`evomotion.sim.worlds.draw_worlds` (the default ranges of
:class:`~evomotion.sim.worlds.Perturbation`, as the walk's worlds), then one push: magnitude
``U(push_min, push_max)`` N s (scaled by the robot's mass over the NAO's,
:meth:`~evomotion.sim.worlds.Perturbation.for_mass`), direction uniform on the horizontal
circle, time ``U(push_window) x duration_s``. The same seed gives the same world whatever
else is evaluated beside it, so any split of the rows over evaluators gives the same numbers.

Per episode (:func:`run_episodes`, :class:`~evomotion.sim.closed_loop.ClosedLoopSimulator`):

- ``up_fraction``: physics steps before the fall over all steps (1: stood the whole time);
- ``tilt_rad``: mean torso tilt from the vertical over the control steps simulated;
- ``action_sq``: mean squared action (rad^2, the offsets from the nominal pose);
- ``score = up_fraction - tilt_weight * tilt_rad - action_weight * action_sq`` (maximised):
  time upright dominates, tilt and effort break ties between policies that stay up.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from evomotion.core.policies.spec import PolicySpec
from evomotion.sim.closed_loop import ClosedLoopResult, ClosedLoopSimulator
from evomotion.sim.worlds import World
from evomotion.studies.episode_worlds import WorldDraw, episode_world, push_range
from evomotion.studies.policy_search import observation_moments

if TYPE_CHECKING:
    from evomotion.sim.warp_closed_loop import WarpClosedLoopSimulator

__all__ = ["Episodes", "WorldDraw", "episode_world", "push_range", "run_episodes"]


@dataclass(frozen=True)
class Episodes:
    """Per episode: ``score``, ``up_fraction``, ``tilt_rad``, ``action_sq``, ``survived``
    (0/1), ``time_up_s``, and the observation moments ``obs_count``, ``obs_mean``,
    ``obs_m2`` the policy saw; ``result`` is the closed-loop run itself."""

    score: np.ndarray
    up_fraction: np.ndarray
    tilt_rad: np.ndarray
    action_sq: np.ndarray
    survived: np.ndarray
    time_up_s: np.ndarray
    obs_count: np.ndarray
    obs_mean: np.ndarray
    obs_m2: np.ndarray
    result: ClosedLoopResult


def run_episodes(sim: ClosedLoopSimulator | WarpClosedLoopSimulator, spec: PolicySpec,
                 params: np.ndarray, mean: np.ndarray, std: np.ndarray, worlds: list[World],
                 nstep: int, tilt_weight: float, action_weight: float,
                 record_states: bool = False) -> Episodes:
    """Episode ``i``: policy ``params[i]`` with normaliser ``mean[i]``, ``std[i]`` in
    ``worlds[i]`` for ``nstep`` physics steps (see the module doc)."""
    n = len(worlds)
    sq = np.zeros(n)
    acts = np.zeros(n, dtype=np.int64)

    def policy(rows: np.ndarray, obs: np.ndarray) -> np.ndarray:
        # each row's own normaliser (ARS V2 line 5); the raw obs, as a structured policy
        # reads its phase columns unnormalised
        a = spec.act(params[rows], obs, mean[rows], std[rows])
        sq[rows] += np.einsum("na,na->n", a, a) / a.shape[1]
        acts[rows] += 1
        return a

    res = sim.run(policy, worlds, nstep, record_states=record_states,
                  record_targets=record_states)
    up = res.fall_step / nstep
    q = res.torso[:, :, 3:7]
    up_z = 1.0 - 2.0 * (q[..., 1] ** 2 + q[..., 2] ** 2)
    tilt = np.arccos(np.clip(up_z, -1.0, 1.0))[:, 1:]  # after each control step
    done = np.maximum(np.ceil(res.steps / sim.k).astype(np.int64), 1)
    valid = np.arange(tilt.shape[1])[None] < done[:, None]
    tilt_mean = (tilt * valid).sum(axis=1) / done
    action_sq = sq / np.maximum(acts, 1)
    score = up - tilt_weight * tilt_mean - action_weight * action_sq
    count, obs_mean, obs_m2 = observation_moments(res.obs_count, res.obs_sum, res.obs_sumsq)
    return Episodes(score, up, tilt_mean, action_sq, (~res.fell).astype(float),
                    res.fall_time_s, count, obs_mean, obs_m2, res)
