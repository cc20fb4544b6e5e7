"""Generation time of the serial, process, ray and dask evaluators, and a cluster estimate.

For each evaluator and population size the same population (drawn uniformly inside the
genome bounds, seed 0) is evaluated ``--repeats`` times after one warm-up call (workers
started, problems built); the median wall time is the generation time, and every result is
checked bit-identical to ``serial``. Every evaluator gets ``problem.threads=1`` so that one
worker is one core (``serial`` is then truly single-core).

Per-chunk overhead is measured on a near-free problem (``functions``, sphere, dim 30): the
time of a 1000-genome batch at ``chunks_per_worker`` 4 and 64, ``o = (T64 - T4) / 60`` per
chunk per worker. With the per-individual cost ``c`` of the study (serial time / N) the
generation time on ``W`` workers in ``chunks_per_worker`` chunks each is estimated as
``T(W) = N c / W + k o`` (optimistic: chunk overheads overlap across workers) up to
``N c / W + W k o`` (pessimistic: the driver serialises every chunk), plus a load
imbalance of about one chunk, ``N c / (W k)``.

Run: ``python benchmarks/bench_evaluators.py [--study humanoid-step] [--pops 100 1000]``
(needs the [ray] and [dask] extras).
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

from evomotion.run.config import resolve_config
from evomotion.run.evaluators import make_evaluator
from evomotion.studies import get_study


def _timed(ev, genomes: np.ndarray, repeats: int, warm: bool = True):
    """(median wall s, median driver CPU s, last Evaluation) of ``ev(genomes)``."""
    if warm:
        ev(genomes[: max(2, len(genomes) // 10)])  # every worker has built its problem
    times, cpu, out = [], [], None
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        out = ev(genomes)
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return float(np.median(times)), float(np.median(cpu)), out


def bench_study(args) -> dict[tuple[str, int], float]:
    """Median generation time per (evaluator, population); rounds interleave the evaluators
    so that the load of a shared machine hits them alike."""
    study = get_study(args.study)
    sets = ["problem.threads=1"] if args.study == "humanoid-step" else []
    cfg = resolve_config(study, None, sets + list(args.set)).problem
    genome = study.make_problem(cfg).genome
    pops = {n: genome.sample(np.random.default_rng(0), n) for n in args.pops}
    evaluators = {}
    try:
        for name in args.evaluators:
            t0 = time.perf_counter()
            evaluators[name] = ev = make_evaluator(name, study.make_problem, cfg,
                                                   workers=args.workers,
                                                   chunks_per_worker=args.chunks_per_worker)
            ev(pops[min(pops)][:4])
            print(f"{name:8s} start-up {time.perf_counter() - t0:.1f} s", flush=True)
        samples: dict[tuple[str, int], list[float]] = {}
        reference = {}
        for r in range(args.repeats):
            for n, genomes in pops.items():
                for name, ev in evaluators.items():
                    t, _, out = _timed(ev, genomes, 1, warm=False)
                    samples.setdefault((name, n), []).append(t)
                    reference.setdefault(n, out)
                    assert out.fitness.tobytes() == reference[n].fitness.tobytes(), name
                    print(f"  round {r}: {name:8s} pop {n:5d} {t:.3f} s", flush=True)
    finally:
        for ev in evaluators.values():
            ev.close()
    times = {key: float(np.median(v)) for key, v in samples.items()}
    for (name, n), t in times.items():
        print(f"{args.study:14s} {name:8s} pop {n:5d}: {t:8.3f} s/generation "
              f"({1e3 * t / n:.2f} ms/individual, median of {args.repeats})", flush=True)
    return times


def chunk_overhead(args) -> dict[str, tuple[float, float]]:
    """Per evaluator: (wall s per chunk per worker, driver CPU s per chunk)."""
    study = get_study("functions")
    cfg = resolve_config(study, None, ["problem.dim=30"]).problem
    genomes = study.make_problem(cfg).genome.sample(np.random.default_rng(0), 1000)
    out = {}
    for name in [e for e in args.evaluators if e != "serial"]:
        t, cpu = {}, {}
        for k in (4, 64):
            ev = make_evaluator(name, study.make_problem, cfg, workers=args.workers,
                                chunks_per_worker=k)
            workers = getattr(ev, "workers", 0) or len(getattr(ev, "actors", [])) \
                or getattr(ev, "threads", 0)
            try:
                t[k], cpu[k], _ = _timed(ev, genomes, max(5, args.repeats))
            finally:
                ev.close()
        o_wall = max((t[64] - t[4]) / 60, 0.0)
        o_cpu = max((cpu[64] - cpu[4]) / (60 * workers), 0.0)
        out[name] = (o_wall, o_cpu)
        print(f"chunk overhead {name:8s}: {1e3 * o_wall:.2f} ms wall per chunk per worker, "
              f"{1e3 * o_cpu:.2f} ms driver CPU per chunk (1000 genomes: T4 "
              f"{1e3 * t[4]:.1f} ms, T64 {1e3 * t[64]:.1f} ms)", flush=True)
    return out


def standing_cost(n: int = 40) -> float:
    """Serial seconds per humanoid-step individual that stays up the whole rollout (genomes
    near the initial pose): the full-length cost an evolved population approaches."""
    study = get_study("humanoid-step")
    cfg = resolve_config(study, None, ["problem.threads=1"]).problem
    problem = study.make_problem(cfg)
    enc = problem.encoding
    pose = np.repeat(enc.q0, enc.intervals - 1)
    noise = np.random.default_rng(0).normal(0.0, 0.005, (n, pose.size)) * problem.genome.span
    genomes = np.clip(pose + noise, problem.genome.lower, problem.genome.upper)
    t0 = time.perf_counter()
    ev = problem.evaluate(genomes)
    c = (time.perf_counter() - t0) / n
    print(f"humanoid-step standing population: {1e3 * c:.2f} ms/individual serial, "
          f"{100 * np.mean(ev.metrics['fell'] > 0):.0f}% fell", flush=True)
    return c


def estimate(c: float, o_wall: float, o_cpu: float, n: int, workers: int, k: int) -> float:
    """Estimated generation time (s) on ``workers`` workers with ``k`` chunks per worker."""
    compute = n * c / workers
    return compute + k * o_wall + workers * k * o_cpu + compute / k


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", default="humanoid-step")
    ap.add_argument("--set", action="append", default=[], help="problem override a.b=v")
    ap.add_argument("--pops", type=int, nargs="+", default=[100, 1000])
    ap.add_argument("--evaluators", nargs="+", default=["serial", "process", "ray", "dask"])
    ap.add_argument("--workers", type=int, default=0, help="0: one per core")
    ap.add_argument("--chunks-per-worker", type=int, default=4)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--cluster-workers", type=int, default=8 * 16)
    args = ap.parse_args()
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}")
    times = bench_study(args)
    big = max(args.pops)
    if ("ray", big) in times and ("process", big) in times:
        ratio = times["ray", big] / times["process", big]
        print(f"ray / process at population {big}: {ratio:.3f} (target <= 1.15)")
    overhead = chunk_overhead(args)
    if ("serial", big) in times:
        costs = {"random population": times["serial", big] / big}
        if args.study == "humanoid-step":
            costs["standing population"] = standing_cost()
        w = args.cluster_workers
        for what, c in costs.items():
            for name, (o_wall, o_cpu) in overhead.items():
                if name == "process":  # one machine only
                    continue
                for n in args.pops:
                    best = min((estimate(c, o_wall, o_cpu, n, w, k), k) for k in (1, 2, 4, 8))
                    print(f"estimate {name:5s} {w} workers, pop {n:5d}, {what} "
                          f"(c = {1e3 * c:.2f} ms): {best[0]:.3f} s/generation, speed-up "
                          f"{n * c / best[0]:.0f}x over serial (chunks_per_worker {best[1]})")


if __name__ == "__main__":
    main()
