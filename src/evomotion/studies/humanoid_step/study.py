"""``humanoid-step``: seed 000, a GA that teaches a simulated NAO a forward step."""

from __future__ import annotations

from pathlib import Path

import typer

from evomotion.studies.base import Study
from evomotion.studies.humanoid_step.artifacts import finalize, on_checkpoint
from evomotion.studies.humanoid_step.problem import HumanoidStepConfig, HumanoidStepProblem

cli = typer.Typer(help="Seed 000: a forward step of the NAO, evolved by a GA.",
                  no_args_is_help=True)


@cli.command("study")
def study_cmd(out: Path | None = typer.Option(None, "--out",
                                             help="folder (default runs/humanoid-step-study-*)"),
              quick: bool = typer.Option(False, "--quick", help="tiny budget (tests, smoke)"),
              seeds: int = typer.Option(10, help="seeds for blx_alpha and arithmetic"),
              generations: int = typer.Option(100, help="generations per run"),
              pop: int = typer.Option(100, help="population size"),
              workers: int = typer.Option(0, help="parallel runs (0 = all cores)"),
              bounds_scale: float = typer.Option(0.25, help="1 = the seed's whole Table 1"),
              intervals: int = typer.Option(20, help="K time intervals (seed: 20)")) -> None:
    """The seed's experiment: five crossovers, BLX-alpha vs arithmetic on several seeds."""
    from evomotion.run.folder import make_run_dir
    from evomotion.studies.humanoid_step.experiment import run_experiment

    out = make_run_dir("humanoid-step-study", out)
    typer.echo(f"writing {out}")
    run_experiment(out, quick=quick, seeds=seeds, generations=generations, pop=pop,
                   workers=workers, bounds_scale=bounds_scale, intervals=intervals)


STUDY = Study(
    name="humanoid-step",
    description="Seed 000: a GA evolves a forward step of a NAO H25 in MuJoCo "
                "(10 leg servos x K knots; a straight step that stands through a 2 s hold).",
    problem_config=HumanoidStepConfig,
    make_problem=HumanoidStepProblem,
    defaults={
        "algorithm": {"pop_size": 100, "crossover": "blx_alpha",
                      "crossover_params": {"alpha": 0.7}, "mutation": "perturb_k",
                      "mutation_rate": 0.3, "mutation_params": {"k": 10, "delta": 0.08},
                      "selection": "roulette", "elitism": 0.1},
        "run": {"generations": 80, "checkpoint_every": 10},
        "problem": {"intervals": 10, "bounds_scale": 0.25},
    },
    presets={"seed": {"problem": {"intervals": 20, "bounds_scale": 1.0, "fitness": "seed",
                                  "hold_s": 1.0},
                      "run": {"generations": 100}}},
    preset_notes={"seed": "the seed's literal setting: its fitness (time to fall + forward "
                          "distance, 1 s hold), K = 20 intervals over Table 1's whole ranges, "
                          "population 100 x 100 generations"},
    core_algorithms=("ga", "cmaes"),
    on_checkpoint=on_checkpoint,
    finalize=finalize,
    cli=cli,
    smoke=(
        "algorithm.pop_size=6",
        "problem.motion_s=0.4",
        "problem.hold_s=0.2",
        "problem.intervals=4",
    ),
)
