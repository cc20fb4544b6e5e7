"""The experiment tables of ``evomotion grid-path study`` (paper 004 and beyond it).

``paper`` (old name ``seed``): the paper's maps and parameters (population 100 / 50
generations / m = 1.2 on 10x10, 225 / 50 / 1.1 on 15x15, 400 / 100 / 1.05 on 20x20), rows
comparing cGA neighbourhoods, update policies and the panmictic GA. ``beyond``: random 20x20
maps at 25% density, success measured against the exact *free* optimum, comparing the paper's
encoding with the continuous mode, more perpendiculars and the repair step.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from evomotion.core.cellular_ga import CGAConfig
from evomotion.core.ga import GAConfig
from evomotion.run.config import Config, RunSection
from evomotion.run.in_memory import run_in_memory
from evomotion.studies.grid_path.path_result import PathResult, outcome
from evomotion.studies.grid_path.problem import GridPathConfig, GridPathProblem
from evomotion.studies.grid_path.solvers import Solution, all_optima

#: The bundled maps after the paper's figures (their names are data names and stay) with the
#: paper's population, generations and ``m`` for each.
PAPER_MAPS = {"seed10a": (100, 50, 1.2), "seed10b": (100, 50, 1.2), "seed15": (225, 50, 1.1),
              "seed20": (400, 100, 1.05)}
PAPER_ROWS = ("cga-L5-line", "cga-C9-line", "cga-L9-line", "cga-C13-line", "cga-Margolus-line",
             "cga-L5-sync", "cga-L5-fixed", "cga-L5-new", "cga-L5-uniform", "ga")
BEYOND_ROWS = ("paper-encoding", "continuous", "continuous-2x", "continuous+repair-r2",
               "continuous+repair-r3", "continuous+repair-r5")
HEADER = ("| map | configuration | success | success (centres) | mean length | best length "
          "| mean conv. gen | s/run |\n|---|---|---|---|---|---|---|---|")
_POLICY = {"line": "line_sweep", "sync": "synchronous", "fixed": "fixed_random_sweep",
           "new": "new_random_sweep", "uniform": "uniform_choice"}
POLICY_SHORT = tuple(_POLICY)
#: ``--experiment`` choices, and old names still accepted (``seed`` became ``paper``)
EXPERIMENTS = ("paper", "beyond")
OLD_EXPERIMENT_NAMES = {"seed": "paper"}
#: Old names of table rows still accepted (``seed-encoding`` became ``paper-encoding``)
OLD_ROW_NAMES = {"seed-encoding": "paper-encoding"}


def evolve(problem: GridPathProblem, alg: Any, seed: int, generations: int,
           evaluator: Any = None) -> PathResult:
    """One run of ``generations`` generations in memory (the tables' many short runs, through
    :func:`~evomotion.run.in_memory.run_in_memory`); ``evaluator`` (default: this process)
    evaluates every fitness batch."""
    cfg = Config("grid-path", RunSection(seed=seed, generations=generations, checkpoint_every=0),
                 alg, problem.cfg)
    t0 = time.perf_counter()
    res = run_in_memory(cfg, problem, evaluator=evaluator)
    return outcome(problem, res.driver, res.state, res.rows, res.generation, res.evaluations,
                   time.perf_counter() - t0)


def algorithm_for(row: str, pop: int, pc: float, pm: float) -> CGAConfig | GAConfig:
    """The optimizer settings of a table row such as ``cga-C9-line`` or ``ga``."""
    if row == "ga":
        return GAConfig(pop_size=pop, crossover="one_point", crossover_rate=pc,
                        mutation_rate=pm, selection="roulette", elitism=1)
    _, nb, pol = row.split("-")
    return CGAConfig(pop_size=pop, neighbourhood=nb, update=_POLICY[pol], crossover_rate=pc,
                     mutation_rate=pm)


@dataclass
class Row:
    map: str
    config: str
    success: float
    success_centres: float
    mean_length: float
    best_length: float
    mean_conv: float
    seconds: float

    def line(self) -> str:
        return (f"| {self.map} | {self.config} | {100 * self.success:.0f}% | "
                f"{100 * self.success_centres:.0f}% | {self.mean_length:.4f} | "
                f"{self.best_length:.4f} | {self.mean_conv:.1f} | {self.seconds:.2f} |")


def map_row(map_name: str, config: str, problem: GridPathProblem, alg, gens: int, seeds: int,
         optima: dict[str, Solution], model: str) -> Row:
    res = [evolve(problem, alg, s, gens) for s in range(seeds)]
    lengths = np.array([r.length if r.valid else np.inf for r in res])
    ok = lengths <= 1.01 * optima[model].length
    ok_c = lengths <= 1.01 * optima["centres"].length
    return Row(map_name, config, float(ok.mean()), float(ok_c.mean()),
               float(np.mean([r.length for r in res])), float(lengths.min()),
               float(np.mean([r.converged_generation for r in res])),
               float(np.mean([r.seconds for r in res])))


def paper_table(seeds: int, maps: list[str], rows: list[str], pc: float, pm: float,
                generations: int = 0) -> Iterator[Row]:
    """Rows of the paper experiment; success is within 1% of the octile optimum."""
    for name in maps:
        pop, gens, m = PAPER_MAPS[name]
        problem = GridPathProblem(GridPathConfig(map=name, m=m))
        optima = all_optima(problem.map)
        for row in rows:
            yield map_row(name, row, problem, algorithm_for(row, pop, pc, pm),
                       generations or gens, seeds, optima, "octile")


def beyond_config(row: str, map_spec: str) -> GridPathConfig:
    base = GridPathConfig(map=map_spec, m=1.05)
    if OLD_ROW_NAMES.get(row, row) == "paper-encoding":
        return base
    n = 2 * GridPathProblem(base).enc.n_parts if "2x" in row else 0
    radius = float(row.split("repair-r")[1]) if "repair-r" in row else 2.0
    return dataclasses.replace(base, mode="continuous", n_parts=n, repair="repair" in row,
                               repair_radius=radius)


def beyond_table(seeds: int, n_maps: int, rows: list[str], pop: int, generations: int,
                 pc: float, pm: float, update: str = "line") -> Iterator[Row]:
    """Random 20x20 maps at 25% density; success is within 1% of the free optimum."""
    for row in rows:
        acc: list[Row] = []
        for k in range(n_maps):
            spec = f"random:20:0.25:{k}"
            problem = GridPathProblem(beyond_config(row, spec))
            optima = all_optima(problem.map)
            alg = algorithm_for(f"cga-L5-{update}", pop, pc, pm)
            acc.append(map_row(spec, row, problem, alg, generations, seeds, optima, "free"))
        yield Row(f"random 20x20 x{n_maps}", row, float(np.mean([r.success for r in acc])),
                  float(np.mean([r.success_centres for r in acc])),
                  float(np.mean([r.mean_length for r in acc])),
                  float(np.mean([r.best_length for r in acc])),
                  float(np.mean([r.mean_conv for r in acc])),
                  float(np.mean([r.seconds for r in acc])))
