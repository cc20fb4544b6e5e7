"""Episodes of a whole population in lockstep: one batched policy call per environment step.

Row ``e`` of a batch is one episode: its policy is picked by ``owner[e]`` (the population row it
belongs to) and it starts from Gymnasium's ``reset(seed=seeds[e])``. Every step the policy maps
the observations of the episodes still running to their actions in one call; the physics then
advances each of them. Two paths give the same numbers:

- :func:`run_batched`: a v5 locomotion task (:mod:`.envs`) stepped with ``mujoco.mj_step`` on
  one ``MjData`` per episode, observation, reward and termination in numpy for all at once;
- :func:`run_gymnasium`: any Gymnasium environment, one ``gymnasium.make`` instance per episode
  (its wrappers, reward, termination and time limit), stepped one by one.

Both return :class:`Episodes`: the return (Gymnasium's reward summed), the length, and the
moments of every observation the policy saw (count, mean, M2 per episode, Welford's update;
Chan et al. 1979 merge them), from which ARS V2 normalises (Mania et al. 2018).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from evomotion.studies.gym.envs import BatchedTask

#: ``policy(owner[k], obs[k, o]) -> actions[k, a]`` for the episodes still running
PolicyFn = Callable[[np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Episodes:
    """Per episode: ``returns``, ``steps`` and the observation moments ``obs_count``,
    ``obs_mean[e, o]``, ``obs_m2[e, o]`` (sum of squared deviations)."""

    returns: np.ndarray
    steps: np.ndarray
    obs_count: np.ndarray
    obs_mean: np.ndarray
    obs_m2: np.ndarray


class _Moments:
    """Welford's running mean and M2 per episode, updated for the running ones at once."""

    def __init__(self, n: int, o: int) -> None:
        self.count = np.zeros(n)
        self.mean = np.zeros((n, o))
        self.m2 = np.zeros((n, o))

    def add(self, rows: np.ndarray, obs: np.ndarray) -> None:
        self.count[rows] += 1.0
        delta = obs - self.mean[rows]
        self.mean[rows] += delta / self.count[rows, None]
        self.m2[rows] += delta * (obs - self.mean[rows])


def run_batched(task: BatchedTask, policy: PolicyFn, owner: np.ndarray, seeds: np.ndarray,
                max_steps: int, action_low: np.ndarray, action_high: np.ndarray,
                datas: list[Any]) -> Episodes:
    """The episodes of ``owner``/``seeds`` on ``task`` (``datas``: at least as many ``MjData``
    of ``task.model``, reused between calls)."""
    m, n = task.model, len(seeds)
    qpos, qvel = np.empty((n, m.nq)), np.empty((n, m.nv))
    for e in range(n):
        d = datas[e]
        mujoco.mj_resetData(m, d)
        d.qpos[:], d.qvel[:] = task.start(int(seeds[e]))
        mujoco.mj_forward(m, d)
        qpos[e], qvel[e] = d.qpos, d.qvel
    obs = task.observe(qpos, qvel)
    moments = _Moments(n, obs.shape[1])
    returns, steps = np.zeros(n), np.zeros(n, dtype=np.int64)
    alive = np.arange(n)
    for _ in range(max_steps):
        moments.add(alive, obs[alive])
        act = np.clip(policy(owner[alive], obs[alive]), action_low, action_high)
        x_before = qpos[alive, 0].copy()
        for k, row in enumerate(alive.tolist()):
            d = datas[row]
            d.ctrl[:] = act[k]
            mujoco.mj_step(m, d, nstep=task.frame_skip)
            qpos[row], qvel[row] = d.qpos, d.qvel
        healthy = task.is_healthy(qpos[alive], qvel[alive])
        returns[alive] += task.reward(x_before, qpos[alive, 0], act, healthy)
        steps[alive] += 1
        obs[alive] = task.observe(qpos[alive], qvel[alive])
        if task.terminate:
            alive = alive[healthy]
        if alive.size == 0:
            break
    return Episodes(returns, steps, moments.count, moments.mean, moments.m2)


def run_gymnasium(envs: list[Any], policy: PolicyFn, owner: np.ndarray,
                  seeds: np.ndarray, max_steps: int, action_low: np.ndarray,
                  action_high: np.ndarray) -> Episodes:
    """The episodes of ``owner``/``seeds``, each in its own Gymnasium environment (``envs``:
    at least as many, reused between calls); an episode ends when Gymnasium says terminated
    or truncated, or after ``max_steps``."""
    n = len(seeds)
    first = [np.asarray(envs[e].reset(seed=int(seeds[e]))[0], dtype=float) for e in range(n)]
    obs = np.stack(first)
    moments = _Moments(n, obs.shape[1])
    returns, steps = np.zeros(n), np.zeros(n, dtype=np.int64)
    alive = np.arange(n)
    for _ in range(max_steps):
        moments.add(alive, obs[alive])
        act = np.clip(policy(owner[alive], obs[alive]), action_low, action_high)
        done = np.zeros(alive.size, dtype=bool)
        for k, e in enumerate(alive):
            o, r, terminated, truncated, _ = envs[e].step(act[k])
            obs[e] = o
            returns[e] += float(r)
            done[k] = terminated or truncated
        steps[alive] += 1
        alive = alive[~done]
        if alive.size == 0:
            break
    return Episodes(returns, steps, moments.count, moments.mean, moments.m2)
