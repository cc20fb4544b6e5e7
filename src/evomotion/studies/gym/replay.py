"""``evomotion replay RUN`` for a gym run: its exported policy played in Gymnasium.

The problem is rebuilt from the run folder's ``config.toml``; ``policy.npz`` is read back (the
file a user would ship). ``--stress N`` plays N episodes from unseen seeds (``seed``,
``seed + 1``, ...) through the study's evaluation (Gymnasium's own reward and termination, or
the bit-identical batched path) and prints their returns; ``--video`` plays the first of them
in a plain Gymnasium loop with the policy and renders it (the environment's MJCF, a camera
following its root body).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from evomotion.errors import InputError
from evomotion.sim.replay_report import report_replay

STUDY_NAME = "gym"
MAX_EPISODES = 1000
#: unseen episodes start from these seeds on (training draws its seeds below 2**31 - 1)
EVAL_SEED_BASE = 2**31


def load_run(path: str | Path) -> tuple[Any, Any, Path]:
    """(problem, exported policy, run folder) of a gym run folder or its ``policy.npz``."""
    from evomotion.core.policies.export import read_policy_npz
    from evomotion.run.config import config_from_dict, config_from_run_dir, run_of_study
    from evomotion.studies import get_study
    from evomotion.studies.gym.problem import GymProblem

    p = Path(path)
    folder = run_of_study(p.parent if p.name == "policy.npz" else p, STUDY_NAME, "replay")
    npz = folder / "policy.npz"
    if not npz.is_file():
        raise InputError(f"replay {path}: no policy.npz yet (the run has not checkpointed a "
                         "policy)")
    cfg = config_from_dict(get_study(STUDY_NAME), config_from_run_dir(folder)[1])
    problem = GymProblem(cfg.problem)
    policy = read_policy_npz(npz)
    if (policy.spec.obs_dim, policy.spec.act_dim) != (problem.obs_dim, problem.act_dim):
        raise InputError(f"{npz}: a policy of {policy.spec.obs_dim} observations and "
                         f"{policy.spec.act_dim} actions; {cfg.problem.env} has "
                         f"{problem.obs_dim} and {problem.act_dim}")
    return problem, policy, folder


def episode_qpos(problem: Any, policy: Any, seed: int) -> tuple[np.ndarray, float]:
    """``qpos`` after the reset and after every step of one Gymnasium episode, and the
    environment step (s)."""
    from evomotion.studies.gym.problem import make_env

    env = make_env(problem.cfg.env)
    u = env.unwrapped
    obs, _ = env.reset(seed=int(seed))
    frames = [u.data.qpos.copy()]
    for _ in range(problem.max_steps):
        act = policy.spec.act_one(policy.params, obs, policy.obs_mean, policy.obs_std)
        obs, _, terminated, truncated, _ = env.step(act)
        frames.append(u.data.qpos.copy())
        if terminated or truncated:
            break
    return np.asarray(frames), float(u.dt)


def replay_run(path: str | Path, episodes: int = 1, seed: int = 0,
               video: str | Path | None = None) -> tuple[dict[str, Any], str | None]:
    """(summary, the reason the video was skipped or ``None``)."""
    from evomotion.core.checks import check_number
    from evomotion.outfile import check_target
    from evomotion.studies.policy_search import policy_rows

    check_number("--stress", episodes, lo=1, hi=MAX_EPISODES, integer=True)
    check_number("--seed", seed, lo=0, hi=2**31 - MAX_EPISODES, integer=True)
    if video is not None:
        video = check_target(video, "video")
    problem, policy, folder = load_run(path)
    rows = np.concatenate([policy_rows(policy.params[None], policy.obs_mean, policy.obs_std,
                                       EVAL_SEED_BASE + seed + k, 1) for k in range(episodes)])
    ev = problem.evaluate(rows)
    returns = ev.metrics["return"]
    summary = {"run": str(folder), "env": problem.cfg.env, "backend": problem.backend,
               "episodes": int(episodes), "first_seed": EVAL_SEED_BASE + seed,
               "return_mean": float(returns.mean()), "return_min": float(returns.min()),
               "return_max": float(returns.max()),
               "steps_mean": float(ev.metrics["steps"].mean())}
    skipped = None
    if video is not None:
        skipped = _video(problem, policy, EVAL_SEED_BASE + seed, video)
    return summary, skipped


def _video(problem: Any, policy: Any, seed: int, video: str | Path) -> str | None:
    import mujoco

    from evomotion.sim.render import RenderUnavailableError, render_video
    from evomotion.studies.gym.problem import make_env

    qpos, dt = episode_qpos(problem, policy, seed)
    u = make_env(problem.cfg.env).unwrapped
    model = getattr(u, "model", None)
    path = getattr(u, "fullpath", None)
    if model is None or path is None:
        return f"{problem.cfg.env} is not a MuJoCo environment"
    root = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, int(model.jnt_bodyid[0]))
    try:
        render_video(qpos, dt, video, model_path=Path(path), camera=f"follow={root},3.0,0.6")
    except RenderUnavailableError as exc:
        return str(exc)
    return None


def replay_command(path: Path, json_out: bool = False, video: Path | None = None,
                   stress: int | None = None, seed: int = 0,
                   push_ns: float | None = None) -> None:
    """CLI body of ``evomotion replay RUN`` for a gym run."""
    if push_ns is not None:
        raise InputError("--push: a gym environment has no pushes; --stress N plays N episodes")
    summary, skipped = replay_run(path, 1 if stress is None else stress, seed, video)
    done, video = report_replay(summary, skipped, video, json_out)
    if done:
        return
    print(f"{summary['env']}: mean return {summary['return_mean']:.1f} over "
          f"{summary['episodes']} unseen episode(s) (min {summary['return_min']:.1f}, max "
          f"{summary['return_max']:.1f}; {summary['steps_mean']:.0f} steps on average)"
          + (f"; video {video}" if video is not None else ""))
