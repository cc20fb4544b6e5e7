"""Gymnasium MuJoCo locomotion tasks stepped without Gymnasium: the same physics, observation,
reward and termination, for a whole population at once.

Gymnasium's v5 ``Hopper``, ``Walker2d``, ``HalfCheetah`` and ``Swimmer`` (Towers et al. 2024,
Gymnasium; the task definitions of Brockman et al. 2016 and Todorov et al. 2012) are a MuJoCo
model, ``frame_skip`` physics steps per action, an observation of ``qpos``/``qvel``, a reward
``w_f * dx/dt + healthy - w_c * |a|^2`` and a healthy-state termination. Every constant is read
from the Gymnasium environment itself (``env.unwrapped``), so a changed default or a
``gymnasium.make`` keyword carries over; the episode's start uses Gymnasium's own seeding
(``gymnasium.utils.seeding.np_random(seed)``, the draws of its ``reset_model``). Each
individual keeps its own ``MjData`` (MuJoCo's solver warm start included), so a rollout is the
same sequence of ``mj_step`` calls as ``env.step``: returns and episode lengths are
bit-identical to Gymnasium's (``tests/studies/gym/test_envs.py`` checks 100 episodes).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

#: the tasks with an exact batched path: Gymnasium id prefix -> how their step reads
TASKS: dict[str, dict[str, Any]] = {
    "Hopper": {"skip_qpos": 1, "clip_qvel": 10.0, "healthy": "hopper", "qvel_noise": "uniform"},
    "Walker2d": {"skip_qpos": 1, "clip_qvel": 10.0, "healthy": "walker",
                 "qvel_noise": "uniform"},
    "HalfCheetah": {"skip_qpos": 1, "clip_qvel": None, "healthy": None,
                    "qvel_noise": "normal"},
    "Swimmer": {"skip_qpos": 2, "clip_qvel": None, "healthy": None, "qvel_noise": "uniform"},
}


def task_of(env_id: str) -> str | None:
    """The :data:`TASKS` key of a Gymnasium id such as ``Hopper-v5`` (``None``: no batched
    path; the episode runs through Gymnasium)."""
    name, _, version = env_id.partition("-")
    return name if name in TASKS and version == "v5" else None


@dataclass(frozen=True)
class BatchedTask:
    """One v5 task's constants, read from a Gymnasium environment (``env.unwrapped``)."""

    model: Any
    frame_skip: int
    dt: float
    init_qpos: np.ndarray
    init_qvel: np.ndarray
    noise: float
    skip_qpos: int
    clip_qvel: float | None
    healthy: str | None
    qvel_noise: str
    forward_weight: float
    ctrl_weight: float
    healthy_reward: float
    terminate: bool
    z_range: tuple[float, float]
    angle_range: tuple[float, float]
    state_range: tuple[float, float]

    @classmethod
    def from_env(cls, env: Any, task: str) -> BatchedTask:
        u, t = env.unwrapped, TASKS[task]
        healthy = t["healthy"]
        return cls(u.model, int(u.frame_skip), float(u.dt), u.init_qpos.copy(),
                   u.init_qvel.copy(), float(u._reset_noise_scale), t["skip_qpos"],
                   t["clip_qvel"], healthy, t["qvel_noise"],
                   float(u._forward_reward_weight), float(u._ctrl_cost_weight),
                   float(getattr(u, "_healthy_reward", 0.0)),
                   bool(getattr(u, "_terminate_when_unhealthy", False)),
                   tuple(getattr(u, "_healthy_z_range", (-np.inf, np.inf))),
                   tuple(getattr(u, "_healthy_angle_range", (-np.inf, np.inf))),
                   tuple(getattr(u, "_healthy_state_range", (-np.inf, np.inf))))

    def start(self, seed: int) -> tuple[np.ndarray, np.ndarray]:
        """``(qpos, qvel)`` of Gymnasium's ``reset(seed=seed)`` (its ``reset_model`` draws)."""
        from gymnasium.utils import seeding

        rng, _ = seeding.np_random(int(seed))
        m, s = self.model, self.noise
        qpos = self.init_qpos + rng.uniform(low=-s, high=s, size=m.nq)
        if self.qvel_noise == "normal":
            qvel = self.init_qvel + s * rng.standard_normal(m.nv)
        else:
            qvel = self.init_qvel + rng.uniform(low=-s, high=s, size=m.nv)
        return qpos, qvel

    def observe(self, qpos: np.ndarray, qvel: np.ndarray) -> np.ndarray:
        """``obs[n, o]`` from ``qpos[n, nq]``, ``qvel[n, nv]`` (Gymnasium's ``_get_obs``)."""
        v = qvel if self.clip_qvel is None else np.clip(qvel, -self.clip_qvel, self.clip_qvel)
        return np.concatenate([qpos[:, self.skip_qpos:], v], axis=1)

    def is_healthy(self, qpos: np.ndarray, qvel: np.ndarray) -> np.ndarray:
        """``bool[n]``: Gymnasium's ``is_healthy`` (always true for a task without one)."""
        n = qpos.shape[0]
        if self.healthy is None:
            return np.ones(n, dtype=bool)
        z, angle = qpos[:, 1], qpos[:, 2]
        ok = (self.z_range[0] < z) & (z < self.z_range[1]) & \
            (self.angle_range[0] < angle) & (angle < self.angle_range[1])
        if self.healthy == "hopper":  # state_vector()[2:] inside the state range
            state = np.concatenate([qpos, qvel], axis=1)[:, 2:]
            ok &= np.all((self.state_range[0] < state) & (state < self.state_range[1]), axis=1)
        return ok

    def reward(self, x_before: np.ndarray, x_after: np.ndarray, action: np.ndarray,
               healthy: np.ndarray) -> np.ndarray:
        """Gymnasium's ``_get_rew``, term by term in its order (so the sums round alike)."""
        x_velocity = (x_after - x_before) / self.dt
        forward = self.forward_weight * x_velocity
        ctrl_cost = self.ctrl_weight * np.sum(np.square(action), axis=1)
        if self.healthy is None:
            return forward - ctrl_cost
        return (forward + healthy * self.healthy_reward) - ctrl_cost
