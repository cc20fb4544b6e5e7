"""Environment steps per CPU second: the gym study's batched evaluation against Gymnasium's
own vector environments, on the same task, policies and episodes (issue 33).

Each path runs ``--episodes`` episodes of ``--steps`` steps at most with the same random linear
policies (one per episode) from the same seeds: the study's batched path (``problem.backend =
"batched"``: one ``MjData`` per episode, numpy observation/reward), its Gymnasium path (one
``gymnasium.make`` per episode, stepped in lockstep), and Gymnasium's ``SyncVectorEnv`` and
``AsyncVectorEnv`` (``--workers`` subprocesses) stepping the same policies. Reported: steps
per CPU second (this process and its children) and per wall second, and the ratios to
``SyncVectorEnv``; the batched path's returns are checked equal to Gymnasium's.

    python benchmarks/bench_gym.py --env Hopper-v5 --episodes 64 --steps 1000
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np


def cpu_seconds() -> float:
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def timed(fn):
    c0, w0 = cpu_seconds(), time.perf_counter()
    out = fn()
    return out, cpu_seconds() - c0, time.perf_counter() - w0


def vector_steps(vec, policy, n: int, steps: int, seeds: np.ndarray) -> tuple[int, np.ndarray]:
    """Step ``vec`` (``n`` envs) until every env's first episode ended; returns env steps."""
    obs, _ = vec.reset(seed=[int(s) for s in seeds])
    alive = np.ones(n, dtype=bool)
    returns, count = np.zeros(n), 0
    for _ in range(steps):
        act = policy(np.arange(n), obs)
        obs, r, term, trunc, _ = vec.step(act)
        returns += np.where(alive, r, 0.0)
        count += int(alive.sum())
        alive &= ~(term | trunc)
        if not alive.any():
            break
    return count, returns


def main() -> None:
    import gymnasium as gym
    import mujoco

    from evomotion.studies.gym.envs import BatchedTask, task_of
    from evomotion.studies.gym.episodes import run_batched, run_gymnasium

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--env", default="Hopper-v5")
    ap.add_argument("--episodes", type=int, default=64)
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--async", dest="workers", type=int, default=1,
                    help="1: also time AsyncVectorEnv (one process per episode); 0: skip")
    ap.add_argument("--gain", type=float, default=0.05, help="std of the random policies")
    a = ap.parse_args()
    env = gym.make(a.env)
    task = BatchedTask.from_env(env, task_of(a.env))
    o, d = env.observation_space.shape[0], env.action_space.shape[0]
    lo, hi = env.action_space.low, env.action_space.high
    rng = np.random.default_rng(0)
    W = rng.normal(0, a.gain, (a.episodes, d, o))
    n = a.episodes

    def policy(rows, obs):
        return np.clip(np.einsum("kao,ko->ka", W[rows], obs), lo, hi)

    seeds = np.arange(n) + 1000
    owner = np.arange(n)
    datas = [mujoco.MjData(task.model) for _ in range(n)]
    envs = [gym.make(a.env) for _ in range(n)]
    mine, c_b, w_b = timed(lambda: run_batched(task, policy, owner, seeds, a.steps, lo, hi,
                                                datas))
    theirs, c_g, w_g = timed(lambda: run_gymnasium(envs, policy, owner, seeds, a.steps, lo,
                                                   hi))
    assert np.array_equal(mine.returns, theirs.returns), "batched != Gymnasium"
    steps = int(mine.steps.sum())
    sync = gym.vector.SyncVectorEnv([lambda: gym.make(a.env) for _ in range(n)])
    (s_sync, r_sync), c_s, w_s = timed(lambda: vector_steps(sync, policy, n, a.steps, seeds))
    rows = [("study batched (backend=batched)", steps, c_b, w_b),
            ("study Gymnasium (backend=gymnasium)", steps, c_g, w_g),
            ("gymnasium SyncVectorEnv", s_sync, c_s, w_s)]
    if a.workers > 0:  # created outside the timing (its start-up is not stepping)
        asyn = gym.vector.AsyncVectorEnv([lambda: gym.make(a.env) for _ in range(n)],
                                         shared_memory=True)

        def run_async():  # closed inside: the workers' CPU counts once they are waited for
            out = vector_steps(asyn, policy, n, a.steps, seeds)
            asyn.close()
            return out

        (s_a, _), c_a, w_a = timed(run_async)
        rows.append((f"gymnasium AsyncVectorEnv ({n} processes, CPU incl. workers)", s_a, c_a, w_a))
    ref = s_sync / c_s
    print(f"{a.env}: {n} episodes, mean length {mine.steps.mean():.0f} steps; batched returns "
          "equal Gymnasium's: yes")
    print("| path | env steps | CPU s | steps / CPU s | ratio to Sync | steps / wall s |")
    print("|---|---|---|---|---|---|")
    for name, s, c, w in rows:
        print(f"| {name} | {s} | {c:.2f} | {s / c:,.0f} | {s / c / ref:.2f} | {s / w:,.0f} |")


if __name__ == "__main__":
    main()
