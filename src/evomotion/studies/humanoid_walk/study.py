"""``humanoid-walk-open-loop`` (``humanoid-walk --preset open-loop``; it was ``humanoid-walk``
until the closed-loop controller became the default, issue 34): a NAO walk whose gait
parameters are evolved by CMA-ES (or the GA), played open loop."""

from __future__ import annotations

from pathlib import Path

import typer

from evomotion.studies.base import Study, lazy_hook
from evomotion.studies.humanoid_walk.problem import HumanoidWalkConfig, make_problem
from evomotion.studies.view import StudyView, lazy

cli = typer.Typer(help="A NAO walk: 14 gait parameters evolved by CMA-ES.",
                  no_args_is_help=True)


@cli.command("compare")
def compare_cmd(run: Path = typer.Argument(..., help="a humanoid-walk-open-loop run folder, or a "
                                                     ".motion file of a walk"),
                hold: float = typer.Option(1.0, "--hold", help="seconds held after each "
                                                               "motion (0 to 60)"),
                trials: int = typer.Option(0, "--trials",
                                           help="also the fall rate in N perturbed worlds "
                                                "(0 to 1000)"),
                seed: int = typer.Option(0, "--seed", help="seed of the perturbed worlds "
                                                           "(>= 0)"),
                json_out: bool = typer.Option(False, "--json", help="JSON on stdout")) -> None:
    """The evolved walk beside Webots' own NAO motions, replayed on the same model."""
    from evomotion.studies.humanoid_walk.compare import compare_command

    typer.echo(compare_command(run, hold_s=hold, json_out=json_out, trials=trials, seed=seed))


ARTIFACTS = "evomotion.studies.humanoid_walk.artifacts"

STUDY = Study(
    name="humanoid-walk-open-loop",
    description="The open-loop NAO walk (humanoid-walk --preset open-loop): 14 gait "
                "parameters (period, step length and height, sway, lean, arm swing, ...) "
                "through leg IK, evolved by CMA-ES over 10 s of walking; exported as Webots "
                ".motion and NAOqi script.",
    problem_config=HumanoidWalkConfig,
    make_problem=make_problem,
    defaults={
        "algorithm": {"name": "cmaes", "pop_size": 8, "sigma0": 0.15},
        "run": {"generations": 100, "checkpoint_every": 10},
        "problem": {"worlds": 8},
    },
    presets={"nominal": {"problem": {"worlds": 1}, "algorithm": {"pop_size": 16}}},
    preset_notes={"nominal": "evolve in the nominal world only (K = 1, population 16): "
                             "about 8x cheaper per generation and faster walks, which fall "
                             "in most perturbed worlds"},
    core_algorithms=("cmaes", "ga"),
    on_checkpoint=lazy_hook(ARTIFACTS, "on_checkpoint"),
    finalize=lazy_hook(ARTIFACTS, "finalize"),
    best_record=lazy_hook(ARTIFACTS, "best_record"),
    cli=cli,
    view=StudyView(motions=True, genome_motion=lazy(ARTIFACTS, "genome_motion")),
    smoke=(
        "algorithm.pop_size=4",
        "problem.walk_s=0.5",
        "problem.hold_s=0.2",
        "problem.worlds=2",
    ),
)
