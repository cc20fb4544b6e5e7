"""humanoid-walk-open-loop benchmark (issue 13): evaluations per second with K = 1 and K = 8
worlds, and
the CMA-ES run loop's physics throughput against raw ``mujoco.rollout``.

1. Evaluations/s of the walk problem (each evaluation = one gait over the whole horizon,
   start-up + 10 s of walking + stop + hold; fallen robots stop early) with K = 1 (nominal)
   and K = 8 worlds (nominal + 7 perturbed, one batch), on two populations: the default gait
   jittered by 5 % of each range (most walk, like late in a run) and uniform samples of the
   box (many fall, like generation 0).
2. The run loop: ``run_study`` (the study's CMA-ES, population 16, K = 1) for ``--generations``
   generations, no run folder; loop steps/s = physics steps simulated / wall time of the whole
   run (ask, decoding, control interpolation, rollouts, scoring, tell, statistics); raw steps/s
   = the same steps / the time inside ``mujoco.rollout``; the ratio (target >= 0.9).

    python benchmarks/bench_walk.py [--pop 16] [--generations 20] [--threads 0] [--repeat 2]
        [--only evaluations|loop]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from evomotion.run.config import resolve_config
from evomotion.run.evaluators import SerialEvaluator
from evomotion.run.runner import run_study
from evomotion.studies import get_study
from evomotion.studies.humanoid_walk.problem import HumanoidWalkConfig, HumanoidWalkProblem


def evaluations(pop: int, threads: int, repeat: int) -> None:
    problems = {k: HumanoidWalkProblem(HumanoidWalkConfig(threads=threads, worlds=k,
                                                          world_seed=0)) for k in (1, 8)}
    p1 = problems[1]
    rng = np.random.default_rng(0)
    batches = {"default gait jittered 5 %": p1.initial_population(pop, rng),
               "uniform in the box": p1.genome.sample(rng, pop)}
    print(f"cpus={os.cpu_count()} threads={p1.sim.nthread} pop={pop} "
          f"physics steps per trajectory={p1.nstep} ({p1.horizon_s:.1f} s)")
    print("| genomes | K | evaluations/s | trajectories/s | fall rate |\n|---|---|---|---|---|")
    for label, g in batches.items():
        for k, p in problems.items():
            best = float("inf")
            for _ in range(repeat):
                t0 = time.perf_counter()
                ev = p.evaluate(g)
                best = min(best, time.perf_counter() - t0)
            print(f"| {label} | {k} | {len(g) / best:.2f} | {k * len(g) / best:.1f} | "
                  f"{float(np.mean(ev.metrics['fall_rate'])):.2f} |", flush=True)


def loop(pop: int, generations: int, threads: int) -> None:
    study = get_study("humanoid-walk-open-loop")
    cfg = resolve_config(study, None, [f"algorithm.pop_size={pop}",
                                       f"run.generations={generations}",
                                       f"problem.threads={threads}", "problem.worlds=1",
                                       "run.checkpoint_every=0"])
    problem = study.make_problem(cfg.problem)
    ev = SerialEvaluator(lambda _c: problem, None)
    t0 = time.perf_counter()
    res = run_study(study, cfg, None, problem=problem, evaluator=ev)
    wall = time.perf_counter() - t0
    steps, inside = problem.sim.steps_simulated, problem.sim.rollout_seconds
    print(f"\nrun loop: CMA-ES pop {pop} x {res.generation} generations, {res.evaluations} "
          f"evaluations, best fitness {res.best_fitness:.3f}, speed "
          f"{res.best_metrics.get('speed_mps', float('nan')):.3f} m/s")
    print("| measure | value |\n|---|---|")
    print(f"| wall time of the run | {wall:.1f} s |")
    print(f"| physics steps simulated | {steps:,} |")
    print(f"| loop physics steps/s | {steps / wall:,.0f} |")
    print(f"| raw mujoco.rollout steps/s (same steps) | {steps / inside:,.0f} |")
    print(f"| loop / raw | {inside / wall:.3f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pop", type=int, default=16)
    ap.add_argument("--generations", type=int, default=20)
    ap.add_argument("--threads", type=int, default=0, help="0 = all cores")
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--only", choices=("evaluations", "loop"), default=None)
    a = ap.parse_args()
    if a.only != "loop":
        evaluations(a.pop, a.threads, a.repeat)
    if a.only != "evaluations":
        loop(a.pop, a.generations, a.threads)


if __name__ == "__main__":
    main()
