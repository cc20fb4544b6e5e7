"""humanoid-step benchmark: physics throughput of the GA loop vs raw ``mujoco.rollout``.

Runs the study's GA (BLX-alpha 0.7, perturb_k 0.3, roulette, elitism 0.1) on the NAO step
problem and reports
- GA-loop physics steps/s = physics steps simulated / wall time of the whole run through the
  engine's run loop (``run_study``: ask, control precomputation, rollouts, scoring, tell,
  statistics, stop rules; with ``--out DIR`` also the run folder, checkpoints and plots);
- raw ``mujoco.rollout`` steps/s on the same model and the same workload = the same steps /
  the time spent inside ``mujoco.rollout`` calls, and separately one plain rollout of the final
  population without early stopping; the ratio GA-loop / raw (target >= 0.8);
- the wall time of the run (paper scale: population 100 x 100 generations).

    python benchmarks/bench_humanoid.py [--pop 100] [--generations 100] [--threads 0] [--out DIR]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from evomotion.core.algorithms import ALGORITHMS
from evomotion.run.config import Config, RunSection
from evomotion.run.evaluators import SerialEvaluator
from evomotion.run.runner import run_study
from evomotion.studies.humanoid_step.problem import HumanoidStepConfig, HumanoidStepProblem
from evomotion.studies.humanoid_step.study import STUDY


class FirstStep(SerialEvaluator):
    """The serial evaluator, noting the first batch in which an individual steps."""

    def __init__(self, problem: HumanoidStepProblem) -> None:
        super().__init__(lambda _cfg: problem, None)
        self.batches, self.first_step = 0, None

    def __call__(self, genomes: np.ndarray):
        ev = super().__call__(genomes)
        if self.first_step is None and ev.metrics["stepped"].any():
            self.first_step = self.batches
        self.batches += 1
        return ev


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pop", type=int, default=100)
    ap.add_argument("--generations", type=int, default=100)
    ap.add_argument("--threads", type=int, default=0, help="0 = all cores")
    ap.add_argument("--intervals", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=None, help="run folder (default: none)")
    a = ap.parse_args()
    pcfg = HumanoidStepConfig(intervals=a.intervals, bounds_scale=0.25, threads=a.threads,
                              fitness="seed", hold_s=1.0)  # paper fitness, old name
    problem = HumanoidStepProblem(pcfg)
    cfg_cls, _ = ALGORITHMS["ga"]
    alg = cfg_cls(pop_size=a.pop, crossover="blx_alpha", crossover_params={"alpha": 0.7},
                  mutation="perturb_k", mutation_rate=0.3,
                  mutation_params={"k": 10, "delta": 0.08}, selection="roulette", elitism=0.1)
    cfg = Config("humanoid-step", RunSection(seed=a.seed, generations=a.generations), alg, pcfg)
    ev = FirstStep(problem)
    t0 = time.perf_counter()
    res = run_study(STUDY, cfg, a.out, quiet=True, problem=problem, evaluator=ev)
    wall = time.perf_counter() - t0
    first_step = ev.first_step
    sim = problem.sim
    steps = sim.steps_simulated
    loop_sps = steps / wall
    inside_sps = steps / sim.rollout_seconds
    # one plain rollout (no early stop) of the final population, same model and threads
    pop, _ = res.driver.opt.population(res.state)
    ctrl = problem.controls(pop)
    t1 = time.perf_counter()
    sim.run(problem.state0, ctrl)
    plain_sps = ctrl.shape[0] * ctrl.shape[1] / (time.perf_counter() - t1)
    best = res.best_fitness
    print(f"cpus={os.cpu_count()} threads={sim.nthread} pop={a.pop} "
          f"generations={a.generations} K={a.intervals} nstep/individual={problem.nstep}")
    print(f"wall time of the run: {wall:.1f} s  (best fitness {best:.3f}, "
          f"first step at generation {first_step})")
    print(f"physics steps simulated: {steps:,} "
          f"(of {(a.generations + 1) * a.pop * problem.nstep:,} without early stop)")
    print(f"GA-loop physics steps/s: {loop_sps:,.0f}")
    print(f"raw mujoco.rollout steps/s, same workload: {inside_sps:,.0f}  "
          f"ratio GA-loop/raw = {loop_sps / inside_sps:.3f}")
    print(f"raw mujoco.rollout steps/s, final population, no early stop: {plain_sps:,.0f}")
    sim.close()


if __name__ == "__main__":
    main()
