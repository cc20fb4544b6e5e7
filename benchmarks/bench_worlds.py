"""Perturbed-world evaluation throughput of humanoid-step (issue 13): evaluations per second
with K = 1 (the nominal model, fallen robots stop early) and K = 8 worlds (one rollout batch of
pop x K trajectories, no early stop), on the same genomes, measured in one run.

Genomes: the initial pose plus N(0, sigma) noise on the knots (most stand, like a population
late in a run) and uniform samples of the genome box (most fall early, like generation 0).

    python benchmarks/bench_worlds.py [--pop 64] [--threads 0] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from evomotion.studies.humanoid_step.problem import HumanoidStepConfig, HumanoidStepProblem


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pop", type=int, default=64)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    base = dict(intervals=10, bounds_scale=0.25, threads=a.threads)
    problems = {k: HumanoidStepProblem(HumanoidStepConfig(**base, worlds=k)) for k in (1, 8)}
    p1 = problems[1]
    rng = np.random.default_rng(0)
    q0 = np.repeat(p1.encoding.q0, p1.cfg.intervals - 1)
    near = np.clip(q0 + rng.normal(0, 0.02, (a.pop, q0.size)), p1.genome.lower, p1.genome.upper)
    batches = {"near the initial pose": near, "uniform in the box": p1.genome.sample(rng, a.pop)}
    print(f"cpus={os.cpu_count()} threads={p1.sim.nthread} pop={a.pop} "
          f"physics steps per trajectory={p1.nstep}")
    print("| genomes | K | evaluations/s | trajectories/s | fall rate |\n|---|---|---|---|---|")
    for label, g in batches.items():
        for k, p in problems.items():
            best = float("inf")
            for _ in range(a.repeat):
                t0 = time.perf_counter()
                ev = p.evaluate(g)
                best = min(best, time.perf_counter() - t0)
            print(f"| {label} | {k} | {len(g) / best:.1f} | {k * len(g) / best:.1f} | "
                  f"{float(np.mean(ev.metrics['fall_rate'])):.2f} |", flush=True)


if __name__ == "__main__":
    main()
