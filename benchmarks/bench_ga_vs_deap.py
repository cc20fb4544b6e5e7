"""GA time per generation (fitness evaluation excluded): evomotion vs DEAP's eaSimple.

Same operators on both sides: BLX-alpha (alpha 0.5; DEAP ``cxBlend``), Gaussian mutation
(DEAP ``mutGaussian``), tournament selection (size 3). Genome 200, populations 100 and 1000.
Evaluation is a trivial function on both sides and its time is measured and subtracted.

Run: ``python benchmarks/bench_ga_vs_deap.py [--generations 20]`` (needs the [bench] extra).
"""

from __future__ import annotations

import argparse
import platform
import random
import time

import numpy as np

from evomotion.core.ga import GA, GAConfig
from evomotion.core.problem import GenomeSpec

DIM = 200


def bench_evomotion(pop: int, gens: int) -> float:
    g = GenomeSpec.box(DIM, -5, 5)
    cfg = GAConfig(pop_size=pop, crossover="blx_alpha", crossover_rate=0.9, mutation="gaussian",
                   mutation_rate=0.2, mutation_params={"sigma": 0.1, "gene_rate": 0.05},
                   selection="tournament", selection_params={"k": 3}, elitism=0)
    ga = GA(g, cfg)
    rng = np.random.default_rng(0)
    s = ga.init(rng)
    x, s = ga.ask(s, rng)
    s = ga.tell(s, x, x[:, 0].copy(), rng)
    t_eval, t0 = 0.0, time.perf_counter()
    for _ in range(gens):
        x, s = ga.ask(s, rng)
        te = time.perf_counter()
        cost = x[:, 0].copy()
        t_eval += time.perf_counter() - te
        s = ga.tell(s, x, cost, rng)
    return (time.perf_counter() - t0 - t_eval) / gens


def bench_deap(pop: int, gens: int) -> float:
    from deap import algorithms, base, creator, tools

    if not hasattr(creator, "FitMin"):
        creator.create("FitMin", base.Fitness, weights=(-1.0,))
        creator.create("Ind", list, fitness=creator.FitMin)
    tb = base.Toolbox()
    random.seed(0)
    tb.register("attr", random.uniform, -5, 5)
    tb.register("individual", tools.initRepeat, creator.Ind, tb.attr, DIM)
    tb.register("population", tools.initRepeat, list, tb.individual)
    t_eval = [0.0]

    def evaluate(ind):
        te = time.perf_counter()
        v = (ind[0],)
        t_eval[0] += time.perf_counter() - te
        return v

    tb.register("evaluate", evaluate)
    tb.register("mate", tools.cxBlend, alpha=0.5)
    tb.register("mutate", tools.mutGaussian, mu=0, sigma=1.0, indpb=0.05)
    tb.register("select", tools.selTournament, tournsize=3)
    p = tb.population(n=pop)
    for ind in p:
        ind.fitness.values = tb.evaluate(ind)
    t_eval[0] = 0.0
    t0 = time.perf_counter()
    algorithms.eaSimple(p, tb, cxpb=0.9, mutpb=0.2, ngen=gens, verbose=False)
    return (time.perf_counter() - t0 - t_eval[0]) / gens


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--generations", type=int, default=20)
    a = ap.parse_args()
    print(f"machine: {platform.node()} {platform.processor() or platform.machine()}, "
          f"python {platform.python_version()}, numpy {np.__version__}")
    print("pop   evomotion_ms  deap_ms  ratio")
    for pop in (100, 1000):
        ours = bench_evomotion(pop, a.generations)
        deap = bench_deap(pop, max(3, a.generations // (2 if pop == 1000 else 1)))
        print(f"{pop:5d} {ours * 1e3:12.3f} {deap * 1e3:8.1f} {deap / ours:6.1f}x")


if __name__ == "__main__":
    main()
