"""The seed's experiment (``evomotion biped-kick study``): optimiser comparison on the kick,
robustness of the best kick over perturbed ball positions, and the keyframe baseline.

1. Plain CMA-ES, +Tent, +Lévy, +Tent+Lévy (the seed's improved CMA-ES) and the engine's GA
   (BLX-alpha) on the same evaluation budget, ``seeds`` runs each: best fitness against
   evaluations (median and interquartile band) -> ``convergence.png``, ``curves.npz``.
2. The best genome of all runs kicks ``kicks`` times from ball positions perturbed uniformly
   by +-``perturb_m`` in x and y; the keyframe kick (``Shoot.motion``) kicks from the same
   offsets -> ``table.md`` (mean distance, mean execution time, fall rate), ``results.json``.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np

from evomotion.core.cmaes import CMAESConfig
from evomotion.core.ga import GAConfig
from evomotion.studies.biped_kick.keyframe import keyframe_kicks
from evomotion.studies.biped_kick.motion import GENES
from evomotion.studies.biped_kick.problem import KickConfig, KickProblem

VARIANTS: dict[str, object] = {
    "cmaes": CMAESConfig(),
    "cmaes+tent": CMAESConfig(chaos=True),
    "cmaes+levy": CMAESConfig(levy=True),
    "cmaes+tent+levy": CMAESConfig(chaos=True, levy=True),
    "ga-blx": GAConfig(pop_size=20, crossover="blx_alpha"),
    # the Tent jump with a short stagnation trigger (the default waits 10 + 30 n / lambda = 48
    # generations, longer than a 480-evaluation run of lambda = 12)
    "cmaes+tent-p5": CMAESConfig(chaos=True, chaos_patience=5),
    "cmaes+tent+levy-p5": CMAESConfig(chaos=True, levy=True, chaos_patience=5),
}


def optimise(problem: KickProblem, cfg: object, seed: int,
             budget: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """(evaluations after each generation, best fitness so far, best genome, best fitness):
    one run through the run loop (no folder) stopped after ``budget`` evaluations."""
    from evomotion.run.config import Config, RunSection
    from evomotion.run.runner import run_study
    from evomotion.studies.biped_kick.study import STUDY

    run = RunSection(seed=seed, generations=10**9, max_evaluations=budget, checkpoint_every=0)
    res = run_study(STUDY, Config("biped-kick", run, cfg, problem.cfg), None, problem=problem)
    evals = np.array([r["evaluations"] for r in res.rows])
    best = np.array([r["best_so_far"] for r in res.rows])
    return evals, best, np.asarray(res.best_genome), float(res.best_fitness)


def on_grid(evals: np.ndarray, best: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """Best-so-far as a step function of the evaluation count (NaN before the first)."""
    idx = np.searchsorted(evals, grid, side="right") - 1
    return np.where(idx >= 0, best[np.maximum(idx, 0)], np.nan)


def perturbed_kicks(problem: KickProblem, genome: np.ndarray,
                    offsets: np.ndarray) -> dict[str, np.ndarray]:
    rows = [problem.evaluate(genome[None], problem.ball_xy() + off).metrics for off in offsets]
    return {k: np.array([r[k][0] for r in rows]) for k in rows[0]}


def summary(m: dict[str, np.ndarray]) -> dict[str, float]:
    return {"mean_distance_m": float(np.mean(m["distance_m"])),
            "mean_abs_lateral_m": float(np.mean(np.abs(m["lateral_m"]))),
            "mean_exec_time_s": float(np.mean(m["exec_time_s"])),
            "fall_rate": float(np.mean(m["fell"])), "n": int(len(m["fell"]))}


def run_experiment(out_dir: Path, seeds: int = 10, budget: int = 480, kicks: int = 100,
                   perturb_m: float = 0.02, variants: list[str] | None = None,
                   cfg: KickConfig = KickConfig(), log=print) -> dict:
    out_dir.mkdir(parents=True, exist_ok=True)
    problem = KickProblem(cfg)
    names = variants or list(VARIANTS)
    grid = np.arange(1, budget + 1)
    curves, best_x, best_f = {}, None, -np.inf
    for name in names:
        rows = []
        for seed in range(seeds):
            ev, b, x, f = optimise(problem, VARIANTS[name], seed, budget)
            rows.append(on_grid(ev, b, grid))
            log(f"{name} seed {seed}: best {f:.3f} m after {ev[-1]} evaluations")
            if f > best_f:
                best_x, best_f = x, f
        curves[name] = np.array(rows)
    np.savez(out_dir / "curves.npz", grid=grid, **curves)
    plot_convergence(grid, curves, out_dir / "convergence.png")
    offsets = np.random.default_rng(12345).uniform(-perturb_m, perturb_m, (kicks, 2))
    opt_kicks = summary(perturbed_kicks(problem, best_x, offsets))
    key_kicks = summary(keyframe_kicks(offsets, cfg=cfg))
    res = {"config": dataclasses.asdict(cfg), "seeds": seeds, "budget": budget,
           "best_fitness": best_f,
           "best_genome": {g[0]: float(v) for g, v in zip(GENES, best_x, strict=True)},
           "final_best": {k: {"median": float(np.median(v[:, -1])),
                              "q25": float(np.percentile(v[:, -1], 25)),
                              "q75": float(np.percentile(v[:, -1], 75))}
                          for k, v in curves.items()},
           "optimised_kick": opt_kicks, "keyframe_kick": key_kicks}
    (out_dir / "results.json").write_text(json.dumps(res, indent=2))
    (out_dir / "table.md").write_text(table_md(res))
    return res


def table_md(res: dict) -> str:
    lines = ["| kick | mean distance (m) | mean abs. lateral (m) | mean execution time (s) | "
             "fall rate | kicks |", "|---|---|---|---|---|---|"]
    for label, key in (("optimised (best CMA-ES/GA run)", "optimised_kick"),
                       ("keyframe Shoot.motion", "keyframe_kick")):
        s = res[key]
        lines.append(f"| {label} | {s['mean_distance_m']:.2f} | {s['mean_abs_lateral_m']:.2f} "
                     f"| {s['mean_exec_time_s']:.2f} | {s['fall_rate']:.0%} | {s['n']} |")
    return "\n".join(lines) + "\n"


def plot_convergence(grid: np.ndarray, curves: dict[str, np.ndarray], out_png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=110)
    for name, c in curves.items():
        ok = np.all(np.isfinite(c), axis=0)  # from the first generation of every run on
        med = np.median(c[:, ok], axis=0)
        lo, hi = np.percentile(c[:, ok], 25, axis=0), np.percentile(c[:, ok], 75, axis=0)
        ax.plot(grid[ok], med, label=name)
        ax.fill_between(grid[ok], lo, hi, alpha=0.2)
    ax.set_xlabel("evaluations")
    ax.set_ylabel("best fitness (m)")
    ax.set_title("Kick optimisation: median and interquartile band over seeds")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out_png)
    plt.close(fig)
