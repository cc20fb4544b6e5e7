"""The arm-ik study (seed 001): descriptor, run adapter and the ``evomotion arm-ik`` commands."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Annotated, Any

import typer

from evomotion.errors import InputError
from evomotion.studies.arm_ik.driver import run_schedule
from evomotion.studies.arm_ik.problem import ArmIKConfig, make_problem
from evomotion.studies.arm_ik.scenario import bundled_names, load_scenario
from evomotion.studies.base import Study


def run(config: Any, out_dir: Path, evaluator: str = "serial", quiet: bool = False) -> int:
    """Study.run adapter: ``config.problem`` is an :class:`ArmIKConfig`, ``config.run.seed``
    the seed; a positive ``run.wall_seconds`` overrides ``problem.wall_seconds``."""
    cfg: ArmIKConfig = config.problem
    wall = float(getattr(config.run, "wall_seconds", 0.0) or 0.0)
    if wall > 0:
        cfg = dataclasses.replace(cfg, wall_seconds=wall)
    return run_schedule(cfg, int(config.run.seed), out_dir, quiet)


cli = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="Arm + fingers inverse kinematics among obstacles (seed 001).")


@cli.command("check")
def check(file: Annotated[str, typer.Argument(help="Scenario file or bundled name")]) -> None:
    """Validate a scenario file and print a summary."""
    typer.echo(load_scenario(file).summary())


@cli.command("study")
def study(
    seeds: Annotated[int, typer.Option(help="Seeds per scenario")] = 20,
    scenario: Annotated[list[str] | None, typer.Option(help="Scenario (repeatable)")] = None,
    matching: Annotated[list[str] | None, typer.Option(help="greedy/optimal/chromosome")] = None,
    wall_seconds: Annotated[float, typer.Option(help="Budget per run")] = 20.0,
) -> None:
    """Success rate and median time to the first solution per scenario (markdown table)."""
    from evomotion.studies.arm_ik.success import HEADER, success_table

    names = scenario or [n for n in bundled_names() if n != "unreachable"]
    if seeds < 1:
        raise InputError("--seeds: expected >= 1")
    typer.echo(HEADER)
    for m in matching or ["optimal"]:
        for n in names:
            typer.echo(success_table(n, seeds, matching=m, wall_seconds=wall_seconds).line())


STUDY = Study(
    name="arm-ik",
    description="Arm + fingers inverse kinematics among obstacles (seed 001)",
    problem_config=ArmIKConfig,
    make_problem=make_problem,
    cli=cli,
    run=run,
)
