"""CMA-ES of evomotion against pycma on BBOB (cocoex), ask/tell overhead, and paper 002's
improvements (Tent chaos, Lévy flights) against plain CMA-ES on multimodal BBOB functions.

Run: ``python benchmarks/bench_cmaes.py [--quick]`` (needs ``cma`` and ``coco-experiment``).
Prints three markdown tables:

1. ERT (expected running time, evaluations to reach f - f_opt <= 1e-8, summed over all runs
   divided by the number of successes; Hansen et al., COCO performance assessment) on a few
   BBOB functions, one run per instance 1..R, no restarts, same x0 and sigma0 = 2 for both.
2. ask+tell wall time per generation at d = 10, 40, 200 (default lambda, cost = random
   numbers, so only the optimizer is timed).
3. IPOP-CMA-ES plain vs +Tent, +Lévy, +both on Rastrigin (f15), Schaffer F7 (f17) and
   Gallagher 101 peaks (f21) at d = 10, 20, fixed budget: successes, ERT, the median of
   the best f reached (absolute f, same instances for all variants) and on how many
   instances the variant ended better / worse than plain.
"""

from __future__ import annotations

import argparse
import os
import time
import warnings

os.environ.setdefault("OMP_NUM_THREADS", "1")  # same single-threaded BLAS for both sides
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import cma
import cocoex
import numpy as np

from evomotion.core.cmaes import CMAES, CMAESConfig
from evomotion.core.problem import GenomeSpec


class Tracked:
    """A cocoex problem that records the evaluation count at which the 1e-8 target was hit."""

    def __init__(self, problem) -> None:
        self.p = problem
        self.hit_at: int | None = None

    def __call__(self, X: np.ndarray) -> np.ndarray:
        out = np.empty(len(X))
        for i, x in enumerate(X):
            out[i] = self.p(x)
            if self.hit_at is None and self.p.final_target_hit:
                self.hit_at = int(self.p.evaluations)
        return out


def run_ours(tp: Tracked, cfg: CMAESConfig, seed: int, budget: int) -> tuple[int, float]:
    d = tp.p.dimension
    opt = CMAES(GenomeSpec.box(d, -5, 5), cfg)
    rng = np.random.default_rng(seed)
    s = opt.init(rng)
    while tp.p.evaluations < budget and tp.hit_at is None:
        x, s = opt.ask(s, rng)
        s = opt.tell(s, x, tp(x), rng)
        if s.done:
            break
    return tp.p.evaluations, s.best_cost


def run_pycma(tp: Tracked, x0: np.ndarray, seed: int, budget: int) -> tuple[int, float]:
    es = cma.CMAEvolutionStrategy(x0, 2.0, {"seed": seed + 1, "verbose": -9,
                                            "maxfevals": budget, "tolfun": 1e-11})
    while not es.stop() and tp.hit_at is None:
        X = es.ask()
        es.tell(X, list(tp(np.asarray(X))))
    return tp.p.evaluations, es.result.fbest


def ert(evals: list[int], hits: list[int | None]) -> float:
    spent = sum(h if h is not None else e for e, h in zip(evals, hits, strict=True))
    succ = sum(h is not None for h in hits)
    return spent / succ if succ else float("inf")


def table_ert(funcs: list[int], dims: list[int], runs: int) -> None:
    print("\n| f | d | ERT ours | succ | ERT pycma | succ | ratio |")
    print("|---|---|---|---|---|---|---|")
    for d in dims:
        budget = 2000 * d
        for f in funcs:
            res = {"ours": ([], []), "pycma": ([], [])}
            for inst in range(1, runs + 1):
                suite = cocoex.Suite("bbob", f"instances:{inst}",
                                     f"dimensions:{d} function_indices:{f}")
                for who in ("ours", "pycma"):
                    tp = Tracked(next(iter(suite)))
                    cfg = CMAESConfig(restarts="none", sigma0=0.2, bound_handling="none")
                    rng = np.random.default_rng(100 + inst)
                    x0 = rng.uniform(-4, 4, d)
                    if who == "ours":
                        opt = CMAES(GenomeSpec.box(d, -5, 5), cfg)
                        # same start for both: place our mean at x0
                        e, _ = run_ours_from(tp, opt, x0, 100 + inst, budget)
                    else:
                        e, _ = run_pycma(tp, x0, 100 + inst, budget)
                    res[who][0].append(e)
                    res[who][1].append(tp.hit_at)
            eo, ep = ert(*res["ours"]), ert(*res["pycma"])
            so = sum(h is not None for h in res["ours"][1])
            sp = sum(h is not None for h in res["pycma"][1])
            print(f"| f{f} | {d} | {eo:.0f} | {so}/{runs} | {ep:.0f} | {sp}/{runs} | "
                  f"{eo / ep:.2f} |")


def run_ours_from(tp: Tracked, opt: CMAES, x0: np.ndarray, seed: int,
                  budget: int) -> tuple[int, float]:
    rng = np.random.default_rng(seed)
    s = opt.init(rng)
    s.mean = opt.to_unit(x0)
    while tp.p.evaluations < budget and tp.hit_at is None and not s.done:
        x, s = opt.ask(s, rng)
        s = opt.tell(s, x, tp(x), rng)
    return tp.p.evaluations, s.best_cost


def table_overhead(dims: list[int], gens: int) -> None:
    print("\n| d | lambda | ours ms/gen | pycma ms/gen | pycma/ours |")
    print("|---|---|---|---|---|")
    for d in dims:
        opt = CMAES(GenomeSpec.box(d, -5, 5), CMAESConfig(restarts="none"))
        rng = np.random.default_rng(0)
        s = opt.init(rng)
        lam = s.lam
        costs = np.random.default_rng(1).random((gens, lam))
        t0 = time.perf_counter()
        for g in range(gens):
            x, s = opt.ask(s, rng)
            s = opt.tell(s, x, costs[g], rng)
        ours = (time.perf_counter() - t0) / gens * 1e3
        es = cma.CMAEvolutionStrategy(np.zeros(d), 2.0, {"seed": 1, "verbose": -9,
                                                          "bounds": [-5, 5]})
        t0 = time.perf_counter()
        for g in range(gens):
            X = es.ask()
            es.tell(X, list(costs[g]))
        theirs = (time.perf_counter() - t0) / gens * 1e3
        print(f"| {d} | {lam} | {ours:.3f} | {theirs:.3f} | {theirs / ours:.1f} |")


VARIANTS = {"plain": {}, "+tent": {"chaos": True}, "+levy": {"levy": True},
            "+tent+levy": {"chaos": True, "levy": True}}


def table_improved(funcs: list[int], dims: list[int], runs: int, budget_per_d: int) -> None:
    print("\n| f | d | variant | succ | ERT | median best f | better/worse than plain |")
    print("|---|---|---|---|---|---|---|")
    for d in dims:
        for f in funcs:
            plain: list[float] = []
            for name, kw in VARIANTS.items():
                evals, hits, best = [], [], []
                for inst in range(1, runs + 1):
                    suite = cocoex.Suite("bbob", f"instances:{inst}",
                                         f"dimensions:{d} function_indices:{f}")
                    tp = Tracked(next(iter(suite)))
                    e, b = run_ours(tp, CMAESConfig(sigma0=0.2, **kw), 1000 + inst,
                                    budget_per_d * d)
                    evals.append(e)
                    hits.append(tp.hit_at)
                    best.append(b)
                succ = sum(h is not None for h in hits)
                if name == "plain":
                    plain = best
                tol = 1e-8
                better = sum(b < p - tol for b, p in zip(best, plain, strict=True))
                worse = sum(b > p + tol for b, p in zip(best, plain, strict=True))
                print(f"| f{f} | {d} | {name} | {succ}/{runs} | {ert(evals, hits):.0f} | "
                      f"{np.median(best):.4g} | {better}/{worse} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="tiny sizes (smoke test)")
    a = ap.parse_args()
    warnings.simplefilter("ignore")
    cocoex.log_level("error")
    runs = 2 if a.quick else 5
    t0 = time.time()
    table_ert([1, 2, 8, 10], [5] if a.quick else [5, 10], runs)
    table_overhead([10, 40, 200], 20 if a.quick else 200)
    table_improved([15, 17, 21], [10] if a.quick else [10, 20], runs,
                   300 if a.quick else 2000)
    print(f"\ntotal {time.time() - t0:.0f} s")


if __name__ == "__main__":
    main()
