"""The arm-ik study (paper 001): descriptor and the ``evomotion arm-ik`` commands.

``evomotion run arm-ik`` runs the paper's schedule (``[algorithm]`` name ``schedule``) through
the run loop: stats.csv (core columns, then the paper's GUI statistics), best.json, board.png,
best.gif; exit code 3 when no solution was found.
"""

from __future__ import annotations

from typing import Annotated

import typer

from evomotion.studies.arm_ik.artifacts import best_record, finalize
from evomotion.studies.arm_ik.problem import ArmIKConfig, make_problem
from evomotion.studies.arm_ik.scenario import OLD_SCENARIO_NAMES, bundled_names, load_scenario
from evomotion.studies.arm_ik.schedule import OWN_ALGORITHMS
from evomotion.studies.base import Study
from evomotion.studies.view import StudyView, lazy

cli = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="Arm + fingers inverse kinematics among obstacles (paper 001).")


@cli.command("check")
def check(file: Annotated[str, typer.Argument(help="Scenario file or bundled name")]) -> None:
    """Validate a scenario file and print a summary."""
    typer.echo(load_scenario(file).summary())


#: ``study``: seeds per scenario and seconds per run at most
MAX_SEEDS = 1000
MAX_WALL_SECONDS = 3600.0


@cli.command("study")
def study(
    seeds: Annotated[int, typer.Option(help="Seeds per scenario (1 to 1000)")] = 20,
    scenario: Annotated[list[str] | None, typer.Option(help="Scenario (repeatable)")] = None,
    matching: Annotated[list[str] | None, typer.Option(help="greedy/optimal/chromosome")] = None,
    wall_seconds: Annotated[float, typer.Option(
        help="Budget per run (s, 0 to 3600; 0: until solved or the schedule ends)")] = 20.0,
) -> None:
    """Success rate and median time to the first solution per scenario (markdown table)."""
    from evomotion.core.checks import check_choice, check_number
    from evomotion.studies.arm_ik.experiment import HEADER, success_table
    from evomotion.studies.arm_ik.objective import MATCHINGS

    names = [OLD_SCENARIO_NAMES.get(n, n) for n in scenario] if scenario else \
        [n for n in bundled_names() if n != "unreachable"]
    check_number("--seeds", seeds, lo=1, hi=MAX_SEEDS, integer=True)
    check_number("--wall-seconds", wall_seconds, lo=0.0, hi=MAX_WALL_SECONDS)
    for m in matching or []:
        check_choice("--matching", m, MATCHINGS)
    for n in names:  # every scenario file read (and checked) before the first run
        load_scenario(n)
    typer.echo(HEADER)
    for m in matching or ["optimal"]:
        for n in names:
            typer.echo(success_table(n, seeds, matching=m, wall_seconds=wall_seconds).line())


STUDY = Study(
    name="arm-ik",
    description="Arm + fingers inverse kinematics among obstacles (paper 001)",
    problem_config=ArmIKConfig,
    make_problem=make_problem,
    # generations are counted by the schedule (algorithm.whole_generations); the paper gives
    # a run 30 s of wall time
    defaults={"run": {"generations": 1_000_000, "wall_seconds": 30.0,
                      "checkpoint_every": 50, "history_every": 5}},
    presets={"paper": {"problem": {"matching": "greedy"},
                       "algorithm": {"survival": "tournament", "restart_after": 0,
                                     "circular_blend": False, "mutation_min_deg": 5.0,
                                     "mutation_max_deg": 5.0}}},
    preset_notes={"paper": "the paper's literal choices: greedy matching, fixed 5 deg mutation, "
                           "linear angle blend, no restarts, survival with replacement"},
    core_algorithms=(),
    algorithms=OWN_ALGORITHMS,
    finalize=finalize,
    best_record=best_record,
    cli=cli,
    view=StudyView(frames=lazy("evomotion.studies.arm_ik.views", "studio_frames")),
    smoke=(
        "algorithm.pop_size=8",
        "algorithm.arm_generations=2",
        "algorithm.finger_generations=2",
        "problem.pictures=false",
        "problem.scenario='three_fingers'",
    ),
)
