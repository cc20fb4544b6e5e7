"""The batched v5 tasks give Gymnasium's own returns, lengths and observations, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

from evomotion.studies.gym.envs import BatchedTask, task_of  # noqa: E402
from evomotion.studies.gym.episodes import run_batched, run_gymnasium  # noqa: E402

TASKS = ["Hopper-v5", "Walker2d-v5", "HalfCheetah-v5", "Swimmer-v5"]


def _policies(env, n: int, seed: int):
    o, a = env.observation_space.shape[0], env.action_space.shape[0]
    rng = np.random.default_rng(seed)
    W, b = rng.normal(0, 0.2, (n, a, o)), rng.normal(0, 0.3, (n, a))
    return lambda rows, obs: np.einsum("kao,ko->ka", W[rows], obs) + b[rows]


@pytest.mark.parametrize("env_id", TASKS)
def test_batched_equals_gymnasium_on_25_random_episodes(env_id):
    """100 episodes in all (25 per task, random linear policies, 300 steps at most): the
    returns, lengths and observation moments are identical, not merely close."""
    import mujoco

    env = gym.make(env_id)
    task = BatchedTask.from_env(env, task_of(env_id))
    n = 25
    policy = _policies(env, n, seed=len(env_id))
    owner, seeds = np.arange(n), np.arange(n) * 7 + 3
    lo, hi = env.action_space.low, env.action_space.high
    mine = run_batched(task, policy, owner, seeds, 300, lo, hi,
                       [mujoco.MjData(task.model) for _ in range(n)])
    theirs = run_gymnasium([gym.make(env_id) for _ in range(n)], policy, owner, seeds, 300,
                           lo, hi)
    np.testing.assert_array_equal(mine.returns, theirs.returns)
    np.testing.assert_array_equal(mine.steps, theirs.steps)
    np.testing.assert_array_equal(mine.obs_mean, theirs.obs_mean)
    np.testing.assert_array_equal(mine.obs_m2, theirs.obs_m2)
    assert mine.steps.min() >= 1


def test_start_state_is_gymnasiums_reset():
    env = gym.make("HalfCheetah-v5")  # its qvel noise is normal, not uniform
    task = BatchedTask.from_env(env, "HalfCheetah")
    obs, _ = env.reset(seed=11)
    qpos, qvel = task.start(11)
    np.testing.assert_array_equal(task.observe(qpos[None], qvel[None])[0], obs)


def test_only_v5_locomotion_has_a_batched_path():
    assert task_of("Hopper-v5") == "Hopper" and task_of("Hopper-v4") is None
    assert task_of("Ant-v5") is None and task_of("CartPole-v1") is None
