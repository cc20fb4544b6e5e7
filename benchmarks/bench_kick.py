"""Kick evaluations per second: batched MuJoCo rollouts of random kick genomes.

Run: ``python benchmarks/bench_kick.py [--batch 24] [--threads 0]`` (0 = all cores).
Prints evaluations/s and simulated physics steps/s (one step = 4 ms of NAO + ball).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from evomotion.studies.biped_kick.problem import KickConfig, KickProblem


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--batch", type=int, default=24)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, default=0)
    a = ap.parse_args()
    p = KickProblem(KickConfig(nthread=a.threads))
    rng = np.random.default_rng(0)
    X = rng.uniform(p.genome.lower, p.genome.upper, (a.batch, p.genome.dim))
    p.evaluate(X[:2])  # warm-up
    steps0 = p.sim.steps_simulated
    t0 = time.perf_counter()
    for _ in range(a.repeats):
        p.evaluate(X)
    dt = time.perf_counter() - t0
    steps = p.sim.steps_simulated - steps0
    print("| batch | threads | evaluations/s | physics steps/s | s per evaluation |")
    print("|---|---|---|---|---|")
    print(f"| {a.batch} | {p.sim.nthread} | {a.batch * a.repeats / dt:.1f} | {steps / dt:.0f} | "
          f"{dt / (a.batch * a.repeats):.3f} |")


if __name__ == "__main__":
    main()
