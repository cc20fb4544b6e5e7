"""The arm-ik experiment (``evomotion arm-ik study``): success rate and median time to the
first solution over seeds (issue 5's table), each run in memory (:func:`evolve`)."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from evomotion.run.config import Config, RunSection
from evomotion.run.in_memory import run_in_memory
from evomotion.studies.arm_ik.artifacts import ArmResult, result_of
from evomotion.studies.arm_ik.problem import ArmIKConfig, ArmIKProblem, make_problem
from evomotion.studies.arm_ik.schedule import OWN_ALGORITHMS, ScheduleConfig, ScheduleDriver


def split_overrides(**kw: Any) -> tuple[dict, dict, dict]:
    """(problem, algorithm, run) keyword groups of a flat set of arm-ik settings."""
    p = {f.name for f in dataclasses.fields(ArmIKConfig)}
    a = {f.name for f in dataclasses.fields(ScheduleConfig)}
    out: tuple[dict, dict, dict] = ({}, {}, {})
    for k, v in kw.items():
        out[0 if k in p else 1 if k in a else 2][k] = v
    return out


def evolve(problem_cfg: ArmIKConfig, seed: int, schedule: ScheduleConfig | None = None,
           wall_seconds: float = 30.0, problem: ArmIKProblem | None = None) -> ArmResult:
    """One run of the schedule in memory (:func:`~evomotion.run.in_memory.run_in_memory`),
    stopped after ``wall_seconds`` (0: no limit); ``problem`` (default: built from
    ``problem_cfg``) may be reused over runs."""
    cfg = Config("arm-ik", RunSection(seed=seed, generations=10**9, checkpoint_every=0,
                                      wall_seconds=wall_seconds),
                 schedule or ScheduleConfig(), problem_cfg)
    res = run_in_memory(cfg, problem, make_problem=make_problem, algorithms=OWN_ALGORITHMS)
    assert isinstance(res.driver, ScheduleDriver)  # the config's algorithm is the schedule
    return result_of(res.driver.problem, res.state, res.evaluations)


@dataclasses.dataclass
class SuccessRow:
    scenario: str
    matching: str
    seeds: int
    solved: int
    median_time_s: float  # over all seeds; unsolved runs count as +inf
    median_cpu_s: float  # the same in process CPU time
    median_generations: float
    median_best_error: float

    @property
    def rate(self) -> float:
        return self.solved / self.seeds

    def line(self) -> str:
        return (f"| {self.scenario} | {self.matching} | {self.solved}/{self.seeds} "
                f"({100 * self.rate:.0f}%) | {self.median_time_s:.2f} | {self.median_cpu_s:.2f} | "
                f"{self.median_generations:.0f} | "
                f"{self.median_best_error:.3g} |")


HEADER = ("| scenario | matching | solved | median wall s to solution | median CPU s "
          "| median generations | median best error |\n|---|---|---|---|---|---|---|")


def success_table(scenario: str, seeds: int, **overrides) -> SuccessRow:
    """Run ``seeds`` seeds (0..seeds-1) of the schedule on ``scenario`` (no pictures);
    ``overrides`` are problem or algorithm keys, or ``wall_seconds`` (default 30)."""
    pk, ak, rk = split_overrides(**overrides)
    cfg = ArmIKConfig(scenario=scenario, pictures=False, **pk)
    sched = ScheduleConfig(**ak)
    times, cpu, gens, errs, ok = [], [], [], [], 0
    for s in range(seeds):
        r = evolve(cfg, s, sched, rk.get("wall_seconds", 30.0), problem=ArmIKProblem(cfg))
        ok += r.solved
        # the times are None exactly when the run was not solved
        times.append(r.time_to_solution_s if r.time_to_solution_s is not None else np.inf)
        cpu.append(r.time_to_solution_cpu_s if r.time_to_solution_cpu_s is not None else np.inf)
        gens.append(r.generations)
        errs.append(float(r.best_assessment.tip_error[0].sum()))
    return SuccessRow(scenario, cfg.matching, seeds, ok, float(np.median(times)),
                      float(np.median(cpu)), float(np.median(gens)), float(np.median(errs)))
