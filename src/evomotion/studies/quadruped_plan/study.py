"""Study ``quadruped-plan``: quadruped walking plans by best-first / A* search (seed 003).

``evomotion run quadruped-plan`` searches one plan (``[problem]`` = QuadrupedPlanConfig)
and writes ``config.toml``, ``plan.json``, ``plan.png``, ``plan.gif`` and ``log.txt``.
``evomotion quadruped-plan study`` prints the seed's 12-configuration table;
``evomotion quadruped-plan check PLAN.json`` re-verifies a plan (exit 1 on a violation).
Exit codes: 0 plan found; 1 no plan (unreachable goal, budget spent) or a violation.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from evomotion.errors import InputError
from evomotion.studies.base import Study
from evomotion.studies.quadruped_plan.checker import PlanViolationError, check_plan
from evomotion.studies.quadruped_plan.experiment import format_table, seed_table
from evomotion.studies.quadruped_plan.plan import plan_document, read_plan, write_plan
from evomotion.studies.quadruped_plan.planner import (
    QuadrupedPlanConfig,
    constants,
    make_problem,
    solve,
    unreachable_reason,
    validate,
)
from evomotion.studies.quadruped_plan.rules import ANGLE_GRID, POS_GRID

NO_PLAN = 1


def run_plan(problem_cfg: QuadrupedPlanConfig, out_dir: str | Path, quiet: bool = True,
             wall_seconds: float = 0.0) -> int:
    """Plan once and write the run folder artifacts; returns the exit code."""
    from evomotion.studies.quadruped_plan.views import animate_plan, plot_plan

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    validate(problem_cfg)
    lines: list[str] = []

    def say(msg: str) -> None:
        lines.append(msg)
        if not quiet:
            typer.echo(msg)

    cfg = problem_cfg
    why = unreachable_reason(cfg)
    if why is not None:
        say(why)
        (out / "log.txt").write_text("\n".join(lines) + "\n")
        return NO_PLAN
    problem = make_problem(cfg)
    secs = cfg.max_seconds if wall_seconds <= 0 else min(cfg.max_seconds, wall_seconds)
    res = solve(cfg, problem, max_seconds=secs)
    say(f"quadruped-plan {cfg.method} rule set {cfg.rule_set}"
        + (f" function ({cfg.function}) k={constants(cfg)}" if cfg.method == "best-first"
           else "") + f": {res.message}")
    if cfg.method != "best-first" and (cfg.pos_grid, cfg.angle_grid) != (POS_GRID, ANGLE_GRID):
        say(f"note: least cost and bound hold for the duplicate grid ({cfg.pos_grid:g} units, "
            f"{cfg.angle_grid:g} rad) only; a finer grid can have shorter plans")
    if res.found:
        search = {"method": cfg.method, "function": cfg.function, "k": list(constants(cfg)),
                  "weight": cfg.weight, "stop_reason": res.stop_reason,
                  "expansions": res.expansions, "generated": res.generated,
                  "reopened": res.reopened, "seconds": res.seconds, "cost": res.cost,
                  "pos_grid": cfg.pos_grid, "angle_grid": cfg.angle_grid}
        if cfg.method != "best-first":  # proved: least plan length >= lower_bound
            search["lower_bound"] = res.lower_bound
        doc = plan_document(problem.model, res.states, res.rules, problem.goal,
                            cfg.goal_tolerance, cfg.sense, cfg.rule_set, problem.zone, search)
        write_plan(out / "plan.json", doc)
        try:
            summary = check_plan(doc)
            say(f"checker: ok, {summary['leg_moves']} leg moves over "
                f"{summary['travel']:.2f} units ({summary['leg_moves_per_unit']:.2f} per unit)")
        except PlanViolationError as e:
            say(f"checker: {e}")
            res.stop_reason = "check-failed"
        plot_plan(doc, out / "plan.png")
        animate_plan(doc, out / "plan.gif", max_frames=cfg.gif_max_frames)
    (out / "log.txt").write_text("\n".join(lines) + "\n")
    return 0 if res.found else NO_PLAN


def run(config: Any, out_dir: Path, evaluator: str = "serial", quiet: bool = False) -> int:
    """Study.run: the custom driver called by the generic runner."""
    from evomotion.run.config import config_to_toml
    from evomotion.run.folder import atomic_write_text

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if not (out / "config.toml").exists():
        atomic_write_text(out / "config.toml", config_to_toml(config))
    return run_plan(config.problem, out, quiet, float(getattr(config.run, "wall_seconds", 0)))


cli = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="Quadruped walking plans by best-first / A* search (seed 003).")


@cli.command("study")
def study_cmd(
    astar: Annotated[bool, typer.Option(help="Add A* and weighted-A* rows")] = False,
    astar_seconds: Annotated[float, typer.Option(help="Time budget per A* row [s]")] = 5.0,
    max_expansions: Annotated[int, typer.Option(help="Expansion budget per row")] = 200_000,
    astar_pos_grid: Annotated[float, typer.Option(
        help="Duplicate grid for positions in the A* rows [units]")] = POS_GRID,
    astar_angle_grid: Annotated[float, typer.Option(
        help="Duplicate grid for the body angle in the A* rows [rad]")] = ANGLE_GRID,
) -> None:
    """Print the seed's 12-configuration table next to the seed's figures."""
    if astar_pos_grid <= 0 or astar_angle_grid <= 0:
        raise InputError("--astar-pos-grid and --astar-angle-grid: expected > 0")
    base = QuadrupedPlanConfig(max_expansions=max_expansions)
    rows = seed_table(base, astar_rows=astar, astar_seconds=astar_seconds,
                      astar_grid=(astar_pos_grid, astar_angle_grid))
    typer.echo(format_table(rows))
    if any(r.stop_reason == "found" and r.check != "ok" for r in rows):
        raise typer.Exit(1)


@cli.command("check")
def check_cmd(plan: Annotated[Path, typer.Argument(help="plan.json to verify")]) -> None:
    """Re-verify every state and transition of a plan; exit 1 on the first violation."""
    doc = read_plan(plan)
    try:
        summary = check_plan(doc)
    except PlanViolationError as e:
        typer.echo(f"{plan}: {e}")
        raise typer.Exit(1) from None
    typer.echo(f"{plan}: ok, {summary['states']} states, {summary['leg_moves']} leg moves, "
               f"{summary['travel']:.2f} units travelled")


STUDY = Study(
    name="quadruped-plan",
    description="Quadruped walking plans by best-first / A* search (seed 003).",
    problem_config=QuadrupedPlanConfig,
    make_problem=make_problem,
    defaults={"run": {"generations": 1}},
    cli=cli,
    run=run,
)
