"""Quality-diversity benchmark (issue 14): evomotion's CMA-ME against pyribs on the arm
repertoire of pyribs' tutorial, plus MAP-Elites and CMA-MAE on the same task.

The setting of pyribs' "arm repertoire" tutorial (``/work/shared/reference/
quality-diversity.md`` section 4): a planar arm of 12 joints, links of length 1, joint angles
in [-pi, pi]; objective ``-Var(theta)`` (maximised), measures = the end effector (x, y);
``CVTArchive`` of 10,000 centroids over [-12, 12]^2; 5 improvement emitters (``"2imp"``),
sigma0 = 0.1 rad, batch 30 each; 700 iterations = 105,000 evaluations. pyribs runs its
tutorial literally (no bounds on the emitters, its default ``selection_rule="filter"``);
evomotion's CMA-ME has the box [-pi, pi] (sigma0 = 0.1 / 2 pi of the range) and the same
"filter" selection; CMA-MAE uses "mu" selection as its paper's released configuration.

Reported per method over ``--seeds`` seeds (median, and min-max): coverage, QD-score with
offset -pi^2 (every term >= 0 inside the box: Var(theta) <= pi^2), normalised QD-score
(QD-score / cells), best objective, and the ask+tell time per generation (the evaluation of
the arm is excluded; the same numpy arm for all).

    python benchmarks/bench_qd_arm.py [--seeds 5] [--iterations 700]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from evomotion.core.cma_me import CMAME, CMAMEConfig
from evomotion.core.map_elites import MAPElites, MAPElitesConfig
from evomotion.core.problem import GenomeSpec, MeasureSpec

DOF, CELLS, EMITTERS, BATCH, SIGMA0_RAD = 12, 10_000, 5, 30, 0.1
OFFSET = -np.pi**2
LINKS = np.ones(DOF)


def arm(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Objective ``-Var(theta)`` and end-effector (x, y) of a batch of arms."""
    cum = np.cumsum(theta, axis=1)
    xy = np.stack([(np.cos(cum) * LINKS).sum(1), (np.sin(cum) * LINKS).sum(1)], axis=1)
    return -np.var(theta, axis=1), xy


def run_ours(opt, iterations: int, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    st = opt.init(rng)
    t_opt = 0.0
    for _ in range(iterations):
        t0 = time.perf_counter()
        x, st = opt.ask(st, rng)
        t_opt += time.perf_counter() - t0
        f, m = arm(x)
        t0 = time.perf_counter()
        st = opt.tell(st, x, -f, rng, measures=m)
        t_opt += time.perf_counter() - t0
    a = opt.result_archive(st)
    obj = a.objective[a.occupied]
    return summary(obj, t_opt / iterations)


def run_pyribs(iterations: int, seed: int) -> dict:
    from ribs.archives import CVTArchive
    from ribs.emitters import EvolutionStrategyEmitter
    from ribs.schedulers import Scheduler

    r = 12.0
    archive = CVTArchive(solution_dim=DOF, centroids=CELLS, ranges=[(-r, r), (-r, r)],
                         seed=seed)
    emitters = [EvolutionStrategyEmitter(archive, x0=np.zeros(DOF), sigma0=SIGMA0_RAD,
                                         ranker="2imp", batch_size=BATCH, seed=seed + 1 + i)
                for i in range(EMITTERS)]
    scheduler = Scheduler(archive, emitters)
    t_opt = 0.0
    for _ in range(iterations):
        t0 = time.perf_counter()
        x = scheduler.ask()
        t_opt += time.perf_counter() - t0
        f, m = arm(x)
        t0 = time.perf_counter()
        scheduler.tell(f, m)
        t_opt += time.perf_counter() - t0
    obj = archive.data("objective")
    return summary(np.asarray(obj), t_opt / iterations)


def summary(obj: np.ndarray, s_per_gen: float) -> dict:
    return {"coverage": obj.size / CELLS, "qd_score": float((obj - OFFSET).sum()),
            "norm_qd": float((obj - OFFSET).sum() / CELLS),
            "best": float(obj.max()) if obj.size else float("nan"),
            "ms_per_gen": 1e3 * s_per_gen}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--iterations", type=int, default=700)
    a = ap.parse_args()
    genome = GenomeSpec.box(DOF, -np.pi, np.pi)
    measures = MeasureSpec(("x", "y"), np.full(2, -12.0), np.full(2, 12.0))
    sigma = SIGMA0_RAD / (2 * np.pi)
    cvt = {"archive": "cvt", "cells": CELLS, "qd_offset": OFFSET}
    methods = {
        "pyribs CMA-ME (2imp)": lambda s: run_pyribs(a.iterations, s),
        "evomotion CMA-ME (2imp)": lambda s: run_ours(CMAME(genome, CMAMEConfig(
            emitters=EMITTERS, pop_size=BATCH, sigma0=sigma, x0="center", **cvt),
            measures=measures), a.iterations, s),
        "evomotion CMA-MAE (imp, alpha 0.01)": lambda s: run_ours(CMAME(genome, CMAMEConfig(
            emitters=EMITTERS, pop_size=BATCH, sigma0=sigma, x0="center", ranking="imp",
            restart_rule="basic", selection="mu", learning_rate=0.01, threshold_min=OFFSET, **cvt),
            measures=measures), a.iterations, s),
        "evomotion MAP-Elites (iso+line)": lambda s: run_ours(MAPElites(genome, MAPElitesConfig(
            pop_size=EMITTERS * BATCH, **cvt), measures=measures), a.iterations, s),
    }
    print(f"arm repertoire: {DOF} joints, CVT {CELLS} cells, {a.iterations} iterations x "
          f"{EMITTERS * BATCH} = {a.iterations * EMITTERS * BATCH} evaluations, "
          f"seeds 0..{a.seeds - 1}; median [min, max]")
    print(f"{'method':38s} {'coverage':>22s} {'QD-score (offset -pi^2)':>30s} "
          f"{'best':>10s} {'ask+tell ms/gen':>22s}")
    for name, fn in methods.items():
        rows = [fn(s) for s in range(a.seeds)]
        col = {k: np.array([r[k] for r in rows]) for k in rows[0]}

        def cell(k, fmt):
            v = col[k]
            return f"{format(np.median(v), fmt)} [{format(v.min(), fmt)}, {format(v.max(), fmt)}]"
        print(f"{name:38s} {cell('coverage', '.3f'):>22s} {cell('qd_score', '.0f'):>30s} "
              f"{np.median(col['best']):10.2e} {cell('ms_per_gen', '.2f'):>22s}")


if __name__ == "__main__":
    main()
