"""A run's exported ``policy.onnx`` in a plain Gymnasium loop on unseen episode seeds (issue 33):
nothing of evomotion is imported, only gymnasium, numpy and onnxruntime, as a user would run it.

    python3 -I benchmarks/onnx_plain_loop.py RUN/policy.onnx --env Hopper-v5 --episodes 20

Prints the mean, std, min and max return; compare with the run's ``centre_return``.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np
import onnxruntime as ort


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("onnx")
    ap.add_argument("--env", default="Hopper-v5")
    ap.add_argument("--episodes", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=2**31 + 10**6,
                    help="unseen: training draws its seeds below 2**31 - 1")
    a = ap.parse_args()
    sess = ort.InferenceSession(a.onnx)
    name = sess.get_inputs()[0].name
    env = gym.make(a.env)
    returns = []
    for seed in range(a.first_seed, a.first_seed + a.episodes):
        obs, _ = env.reset(seed=seed)
        total, done = 0.0, False
        while not done:
            act = sess.run(None, {name: obs[None].astype(np.float32)})[0][0]
            obs, reward, terminated, truncated, _ = env.step(act)
            total += float(reward)
            done = terminated or truncated
        returns.append(total)
    r = np.array(returns)
    print(f"{a.env}: {a.onnx} in a plain Gymnasium loop, {a.episodes} episodes from seed "
          f"{a.first_seed}: mean {r.mean():.1f}, std {r.std():.1f}, min {r.min():.1f}, "
          f"max {r.max():.1f}")


if __name__ == "__main__":
    main()
