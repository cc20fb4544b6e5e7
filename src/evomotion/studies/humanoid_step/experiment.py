"""The paper's experiment (`evomotion humanoid-step study`): five crossovers compared.

Paper 000, section 3: population 100, mutation probability 0.3, K = 20 intervals, roulette
selection, elitism 0.1; crossovers one-point, arithmetic, geometric, linear and BLX-alpha
(alpha = 0.7). The paper reports that BLX-alpha reaches a forward step after about 70
generations and the arithmetic crossover after about 140. Here BLX-alpha and arithmetic run
on ``seeds`` seeds each, the other three on ``max(1, seeds // 3)``. Per run we record the
best/mean/min fitness per generation, the first generation in which an individual makes a
*step* (feet >= 5 cm forward, not fallen; see :mod:`.problem`) and the first generation that
reaches the highest fitness (stands the whole time with the feet >= ``forward_cap_m``
forward). The runs go one after the other through the run loop in memory
(:func:`~evomotion.run.in_memory.run_in_memory`); each population is evaluated by the run
loop's ``process`` evaluator over ``workers`` processes (one ``mujoco.rollout`` thread each),
one pool for the whole experiment, or in this process when ``workers`` is 1.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.core.algorithms import ALGORITHMS
from evomotion.outfile import atomic_write_text, check_target, save_figure
from evomotion.run.config import Config, RunSection
from evomotion.run.evaluators import SerialEvaluator, make_evaluator
from evomotion.run.in_memory import run_in_memory
from evomotion.studies.humanoid_step.problem import HumanoidStepConfig, HumanoidStepProblem

CROSSOVERS: dict[str, dict] = {  # label -> engine crossover + params
    "one_point": {"crossover": "one_point"},
    "arithmetic": {"crossover": "arithmetic_whole"},
    "geometric": {"crossover": "geometric"},
    "linear": {"crossover": "linear"},
    "blx_alpha": {"crossover": "blx_alpha", "crossover_params": {"alpha": 0.7}},
}
ALGO = {"mutation": "perturb_k", "mutation_rate": 0.3, "mutation_params": {"k": 10, "delta": 0.08},
        "selection": "roulette", "elitism": 0.1}


class _Recorder:
    """The run's evaluator: passes each batch to ``evaluate`` (the experiment's evaluator, not
    closed here) and keeps per batch (steps made, highest fitness)."""

    def __init__(self, evaluate: Callable[[np.ndarray], Any]) -> None:
        self.evaluate = evaluate
        self.batches: list[tuple[int, float]] = []

    def __call__(self, genomes: np.ndarray) -> Any:
        ev = self.evaluate(genomes)
        self.batches.append((int(ev.metrics["stepped"].sum()), float(ev.fitness.max())))
        return ev

    def close(self) -> None:
        pass


def run_one(label: str, seed: int, pop: int, generations: int,
            problem_cfg: HumanoidStepConfig, evaluator: Any = None) -> dict:
    """One GA run in memory (:func:`~evomotion.run.in_memory.run_in_memory`); returns its
    curve and the first generation with a step (or None). ``evaluator`` (default: this
    process) evaluates every population. A Ctrl-C (or SIGTERM) ends the whole study: the runs
    finished before it stay in ``results.csv`` and ``curves/``."""
    cfg_cls, _ = ALGORITHMS["ga"]
    algo = cfg_cls(pop_size=pop, **ALGO, **CROSSOVERS[label])
    problem = HumanoidStepProblem(problem_cfg)
    rec = _Recorder(evaluator or SerialEvaluator(lambda _cfg: problem, None))
    cfg = Config("humanoid-step", RunSection(seed=seed, generations=generations,
                                             checkpoint_every=0), algo, problem_cfg)
    res = run_in_memory(cfg, problem, evaluator=rec)
    if res.stop_reason == "interrupted":
        problem.sim.close()
        raise KeyboardInterrupt
    full = problem_cfg.motion_s + problem_cfg.hold_s + \
        problem_cfg.distance_weight * problem_cfg.forward_cap_m  # the highest fitness
    stepped = [n for n, _ in rec.batches]
    first_step = next((g for g, n in enumerate(stepped) if n), None)
    first_full = next((g for g, (_, f) in enumerate(rec.batches) if f >= full - 1e-9), None)
    curve = [(int(r["generation"]), r["max"], r["mean"], r["min"], n)
             for r, n in zip(res.rows, stepped, strict=True)]
    problem.sim.close()
    return {"crossover": label, "seed": seed, "first_step_generation": first_step,
            "first_full_generation": first_full, "final_best": float(curve[-1][1]),
            "curve": curve}


def plan(seeds: int) -> list[tuple[str, int]]:
    others = max(1, seeds // 3)
    jobs = [(label, s) for label in CROSSOVERS
            for s in range(seeds if label in ("blx_alpha", "arithmetic") else others)]
    return sorted(jobs, key=lambda j: j[1])  # seed-major: a cut-short study stays balanced


def run_experiment(out: Path, quick: bool = False, seeds: int = 10, generations: int = 100,
                   pop: int = 100, workers: int = 0, bounds_scale: float = 0.25,
                   intervals: int = 20, echo=print) -> list[dict]:
    """Run the plan, write ``results.csv``, ``curves/*.csv``, ``summary.md``, ``curves.png``.
    ``bounds_scale = 1`` uses the paper's whole Table 1 (see docs/humanoid-step.md)."""
    # the paper's experiment: its fitness and its 1 s hold (the study default is the step fitness)
    problem_cfg = HumanoidStepConfig(intervals=intervals, bounds_scale=bounds_scale, threads=1,
                                     fitness="paper", hold_s=1.0)
    if quick:
        seeds, generations, pop = 1, 2, 8
        problem_cfg = dataclasses.replace(problem_cfg, intervals=4, motion_s=0.4, hold_s=0.2)
    out = Path(out)
    check_outputs(out)
    workers = min(workers or os.cpu_count() or 1, pop)
    results: list[dict] = []
    _write_results(out, results)
    # one pool of the run loop's process workers for every run (None: this process)
    evaluator = make_evaluator("process", HumanoidStepProblem, problem_cfg, workers) \
        if workers > 1 else None
    try:
        for label, s in plan(seeds):
            results.append(_save(out, run_one(label, s, pop, generations, problem_cfg,
                                               evaluator), results))
    finally:
        if evaluator is not None:
            evaluator.close()
    results.sort(key=lambda r: (list(CROSSOVERS).index(r["crossover"]), r["seed"]))
    _write_results(out, results)
    table = summary_table(results, generations)
    atomic_write_text(out / "summary.md",
                      f"# humanoid-step study: pop {pop}, {generations} generations, K = "
                      f"{problem_cfg.intervals}, bounds_scale {problem_cfg.bounds_scale}\n\n"
                      f"{table}\n", "study summary")
    plot_curves(results, out / "curves.png")
    echo(table)
    return results


#: what :func:`run_experiment` writes in its folder (besides ``curves/``)
OUTPUTS = ("results.csv", "summary.md", "curves.png")
RESULT_COLUMNS = ["crossover", "seed", "first_step_generation", "first_full_generation",
                  "final_best"]


def check_outputs(out: Path) -> None:
    """Every file of :data:`OUTPUTS` can be written in the folder ``out`` (before any run)."""
    for name in OUTPUTS:
        check_target(out / name, f"study output {name}")


def _csv(rows: list[list]) -> str:
    buf = io.StringIO()
    csv.writer(buf).writerows(rows)
    return buf.getvalue()


def _write_results(out: Path, results: list[dict]) -> None:
    """``results.csv``: one row per finished run (rewritten whole, atomically)."""
    rows = [[r[k] for k in RESULT_COLUMNS] for r in results]
    atomic_write_text(out / "results.csv", _csv([RESULT_COLUMNS, *rows]), "study results")


def _save(out: Path, r: dict, done: list[dict]) -> dict:
    """Write one finished run (its curve, and the results so far) as soon as it ends."""
    atomic_write_text(out / "curves" / f"{r['crossover']}_seed{r['seed']}.csv",
                      _csv([["generation", "max", "mean", "min", "stepped"], *r["curve"]]),
                      "study curve", mkdir=True)
    _write_results(out, [*done, r])
    return r


def _median_generation(values: list[int | None], generations: int) -> str:
    """Median over runs; a run that never got there counts as ``> generations``."""
    med = float(np.median([v if v is not None else np.inf for v in values]))
    return f"> {generations}" if not np.isfinite(med) else f"{med:g}"


def summary_table(results: list[dict], generations: int) -> str:
    rows = ["| crossover | runs | runs with a step | median generations to first step "
            "| runs at full fitness | median generations to full fitness | median final best |",
            "|---|---|---|---|---|---|---|"]
    for label in CROSSOVERS:
        rs = [r for r in results if r["crossover"] == label]
        if not rs:
            continue
        steps = [r["first_step_generation"] for r in rs]
        fulls = [r["first_full_generation"] for r in rs]
        rows.append(f"| {label} | {len(rs)} | {sum(g is not None for g in steps)} | "
                    f"{_median_generation(steps, generations)} | "
                    f"{sum(g is not None for g in fulls)} | "
                    f"{_median_generation(fulls, generations)} | "
                    f"{np.median([r['final_best'] for r in rs]):.3f} |")
    return "\n".join(rows)


def plot_curves(results: list[dict], png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    for label in CROSSOVERS:
        curves = [np.array(r["curve"], float) for r in results if r["crossover"] == label]
        if not curves:
            continue
        best = np.median(np.stack([c[:, 1] for c in curves]), axis=0)
        mean = np.median(np.stack([c[:, 2] for c in curves]), axis=0)
        line, = ax.plot(curves[0][:, 0], best, label=f"{label} max ({len(curves)} runs)")
        ax.plot(curves[0][:, 0], mean, ls="--", color=line.get_color(), lw=0.8)
    ax.set_xlabel("generation")
    ax.set_ylabel("fitness (median over runs; dashed = mean)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    try:
        save_figure(fig, png, "study curves", dpi=120)
    finally:
        plt.close(fig)
