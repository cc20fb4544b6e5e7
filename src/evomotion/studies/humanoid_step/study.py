"""``humanoid-step``: paper 000, a GA that teaches a simulated NAO a forward step."""

from __future__ import annotations

from pathlib import Path

import typer

from evomotion.studies.base import Study
from evomotion.studies.humanoid_step.artifacts import finalize, on_checkpoint
from evomotion.studies.humanoid_step.problem import HumanoidStepConfig, HumanoidStepProblem
from evomotion.studies.view import StudyView, lazy

cli = typer.Typer(help="Paper 000: a forward step of the NAO, evolved by a GA.",
                  no_args_is_help=True)


#: ``study``: seeds, generations, population and workers at most
MAX_SEEDS = 1000
MAX_GENERATIONS = 100_000
MAX_POP = 100_000
MAX_WORKERS = 1024


@cli.command("study")
def study_cmd(out: Path | None = typer.Option(None, "--out",
                                             help="folder (default runs/humanoid-step-study-*;"
                                                  " its parent must exist)"),
              quick: bool = typer.Option(False, "--quick", help="tiny budget (tests, smoke)"),
              seeds: int = typer.Option(10, help="seeds for blx_alpha and arithmetic "
                                                 "(1 to 1000)"),
              generations: int = typer.Option(100, help="generations per run (1 to 100000)"),
              pop: int = typer.Option(100, help="population size (4 to 100000)"),
              workers: int = typer.Option(0, help="evaluation processes (0 = all cores, 1 = "
                                                  "this process; at most 1024)"),
              bounds_scale: float = typer.Option(0.25, help="in (0, 1]; 1 = the paper's whole "
                                                            "Table 1"),
              intervals: int = typer.Option(20, help="K time intervals (paper: 20; 2 to "
                                                     "10000)")) -> None:
    """The paper's experiment: five crossovers, BLX-alpha vs arithmetic on several seeds."""
    from evomotion.core.checks import check_number
    from evomotion.run.folder import make_output_folder
    from evomotion.studies.humanoid_step.experiment import check_outputs, run_experiment
    from evomotion.studies.humanoid_step.problem import MAX_INTERVALS

    check_number("--seeds", seeds, lo=1, hi=MAX_SEEDS, integer=True)
    check_number("--generations", generations, lo=1, hi=MAX_GENERATIONS, integer=True)
    check_number("--pop", pop, lo=4, hi=MAX_POP, integer=True)
    check_number("--workers", workers, lo=0, hi=MAX_WORKERS, integer=True)
    check_number("--bounds-scale", bounds_scale, lo=0.0, hi=1.0, lo_open=True)
    check_number("--intervals", intervals, lo=2, hi=MAX_INTERVALS, integer=True)
    out = make_output_folder("humanoid-step-study", out)
    check_outputs(out)
    typer.echo(f"writing {out}")
    run_experiment(out, quick=quick, seeds=seeds, generations=generations, pop=pop,
                   workers=workers, bounds_scale=bounds_scale, intervals=intervals)


STUDY = Study(
    name="humanoid-step",
    description="Paper 000: a GA evolves a forward step of a NAO H25 in MuJoCo "
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
    presets={"paper": {"problem": {"intervals": 20, "bounds_scale": 1.0, "fitness": "paper",
                                   "hold_s": 1.0},
                       "run": {"generations": 100}}},
    preset_notes={"paper": "the paper's literal setting: its fitness (time to fall + forward "
                           "distance, 1 s hold), K = 20 intervals over Table 1's whole ranges, "
                           "population 100 x 100 generations"},
    core_algorithms=("ga", "cmaes"),
    on_checkpoint=on_checkpoint,
    finalize=finalize,
    cli=cli,
    view=StudyView(motions=True, genome_motion=lazy("evomotion.studies.humanoid_step.artifacts",
                                                   "genome_motion")),
    smoke=(
        "algorithm.pop_size=6",
        "problem.motion_s=0.4",
        "problem.hold_s=0.2",
        "problem.intervals=4",
    ),
)
