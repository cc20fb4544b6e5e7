"""Ask/tell overhead per generation of the evolution strategies (issue 33): OpenAI-ES, ARS,
PGPE and SNES at population 200 and 10,000 parameters, on the CPU, the cost function left
out (a constant cost vector), so what is timed is the optimizer alone.

EvoTorch and evosax are optional references: when installed, their counterparts are timed
at the same population and dimension in the same run; when not, the script says so and
times ours only (it never installs them); evosax runs jit-compiled on JAX's CPU backend, in
float32. Figures: median milliseconds per generation over
``--generations`` after ``--warmup``; the machine is shared, so compare ratios within a run.

    python3 benchmarks/bench_es_overhead.py [--pop 200] [--dim 10000] [--generations 30]
"""

from __future__ import annotations

import argparse
import importlib.util
import time

import numpy as np

from evomotion.core.algorithms import make_optimizer
from evomotion.core.problem import GenomeSpec

#: label -> (optimizer, settings); "+table": the shared noise table (2**22 numbers, 32 MiB)
TABLE = {"noise_table": 2**22}
OURS = {"openai_es": ("openai_es", {}), "ars": ("ars", {}), "pgpe": ("pgpe", {}),
        "snes": ("snes", {}), "openai_es+table": ("openai_es", TABLE),
        "ars+table": ("ars", TABLE), "pgpe+table": ("pgpe", TABLE), "snes+table": ("snes", TABLE)}


def time_ours(label: str, pop: int, dim: int, gens: int, warmup: int) -> float:
    genome = GenomeSpec.box(dim, -10.0, 10.0)
    name, options = OURS[label]
    opt = make_optimizer(name, genome, pop_size=pop, **options)
    rng = np.random.default_rng(0)
    state = opt.init(rng)
    cost = np.random.default_rng(1).standard_normal(pop)
    times = []
    for g in range(warmup + gens):
        t0 = time.perf_counter()
        x, state = opt.ask(state, rng)
        state = opt.tell(state, x, cost, rng)
        if g >= warmup:
            times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def references() -> list[str]:
    have = [m for m in ("evotorch", "evosax") if importlib.util.find_spec(m) is not None]
    for m in ("evotorch", "evosax"):
        if m not in have:
            print(f"{m}: not installed; timing evomotion only (install it to compare)")
    return have


def time_evotorch(pop: int, dim: int, gens: int, warmup: int) -> dict[str, float]:
    import logging
    import warnings

    import torch  # noqa: F401  (EvoTorch's own dependency)
    warnings.filterwarnings("ignore", category=FutureWarning)  # torch.jit, inside EvoTorch
    from evotorch import Problem
    from evotorch.algorithms import PGPE, SNES

    for name in ("evotorch", "evotorch.core"):  # its INFO lines for every Problem made
        logging.getLogger(name).setLevel(logging.WARNING)

    problem = Problem("min", lambda x: x.sum(dim=-1), solution_length=dim,
                      initial_bounds=(-1.0, 1.0), vectorized=True)  # float32, its default
    out = {}
    for label, make in (("pgpe", lambda: PGPE(problem, popsize=pop, center_learning_rate=0.075,
                                              stdev_learning_rate=0.1, stdev_init=0.1,
                                              optimizer="clipup",
                                              optimizer_config={"max_speed": 0.15})),
                        ("snes", lambda: SNES(problem, popsize=pop, stdev_init=0.1))):
        searcher = make()
        times = []
        for g in range(warmup + gens):
            t0 = time.perf_counter()
            searcher.step()  # includes EvoTorch's (trivial) evaluation of the batch
            if g >= warmup:
                times.append(time.perf_counter() - t0)
        out[label] = 1e3 * float(np.median(times))
    return out


def time_evosax(pop: int, dim: int, gens: int, warmup: int) -> dict[str, float]:
    """evosax (0.2+ API: ``init/ask/tell`` with explicit keys, state and params) as its users
    run it: ``ask`` and ``tell`` each ``jax.jit``-compiled (the warm-up absorbs compilation);
    float32, as evosax computes, where ours is float64."""
    import jax
    import jax.numpy as jnp
    from evosax.algorithms import ARS, PGPE, SNES, Open_ES

    out = {}
    sample = jnp.zeros(dim)
    fitness = jnp.asarray(np.random.default_rng(1).standard_normal(pop), dtype=jnp.float32)
    for label, cls in (("openai_es", Open_ES), ("ars", ARS), ("pgpe", PGPE), ("snes", SNES)):
        try:
            es = cls(population_size=pop, solution=sample)
        except TypeError as e:  # an API that moved: say so, time the others
            print(f"  evosax    {label:10s} not timed ({e})")
            continue
        params = es.default_params
        key = jax.random.key(0)
        state = es.init(key, sample, params)
        ask, tell = jax.jit(es.ask), jax.jit(es.tell)
        times = []
        for g in range(warmup + gens):
            key, k_ask, k_tell = jax.random.split(key, 3)
            t0 = time.perf_counter()
            x, state = ask(k_ask, state, params)
            state, _ = tell(k_tell, x, fitness, state, params)
            jax.block_until_ready(state)
            if g >= warmup:
                times.append(time.perf_counter() - t0)
        out[label] = 1e3 * float(np.median(times))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pop", type=int, default=200)
    ap.add_argument("--dim", type=int, default=10_000)
    ap.add_argument("--generations", type=int, default=30)
    ap.add_argument("--warmup", type=int, default=3)
    a = ap.parse_args()
    print(f"ask+tell per generation, population {a.pop}, {a.dim} parameters "
          f"(median of {a.generations})")
    for name in OURS:
        ms = time_ours(name, a.pop, a.dim, a.generations, a.warmup)
        print(f"  evomotion {name:15s} {ms:8.2f} ms")
    rng = np.random.default_rng(0)
    floor = []
    for _ in range(a.generations):
        t0 = time.perf_counter()
        rng.standard_normal((a.pop // 2, a.dim))
        floor.append(time.perf_counter() - t0)
    print(f"  floor: drawing {a.pop // 2} x {a.dim} normals alone "
          f"{1e3 * float(np.median(floor)):6.2f} ms (SNES draws twice as many)")
    have = references()
    if "evotorch" in have:
        for name, ms in time_evotorch(a.pop, a.dim, a.generations, a.warmup).items():
            print(f"  evotorch  {name:10s} {ms:8.2f} ms")
    if "evosax" in have:
        for name, ms in time_evosax(a.pop, a.dim, a.generations, a.warmup).items():
            print(f"  evosax    {name:10s} {ms:8.2f} ms")


if __name__ == "__main__":
    main()
