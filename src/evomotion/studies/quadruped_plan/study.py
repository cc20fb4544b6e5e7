"""Study ``quadruped-plan``: quadruped walking plans by best-first / A* search (seed 003).

``evomotion run quadruped-plan`` searches one plan through the run loop (``[problem]`` =
QuadrupedPlanConfig, ``[algorithm]`` = the search stepped in batches of expansions, see
:mod:`.search_driver`): stats.csv per batch, checkpoints, resume; at the end ``plan.json``,
``plan.png``, ``plan.gif`` and the checker's verdict in ``log.txt``.
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
    exact_plan,
    make_problem,
)
from evomotion.studies.quadruped_plan.rules import ANGLE_GRID, POS_GRID
from evomotion.studies.quadruped_plan.search_driver import SearchConfig, make_driver

NO_PLAN = 1


def _outcome(ctx: Any) -> tuple[Any, dict | None]:
    """The search result (exact plan) and its plan document, computed once per context."""
    if "plan" not in ctx.cache:
        cfg, problem = ctx.config.problem, ctx.problem
        res = exact_plan(problem, ctx.driver.result(ctx.state))
        doc = None
        if res.found:
            search = {"method": cfg.method, "function": cfg.function,
                      "k": list(constants(cfg)), "weight": cfg.weight,
                      "stop_reason": res.stop_reason, "expansions": res.expansions,
                      "generated": res.generated, "reopened": res.reopened,
                      "seconds": res.seconds, "cost": res.cost, "pos_grid": cfg.pos_grid,
                      "angle_grid": cfg.angle_grid}
            if cfg.method != "best-first":  # proved: least plan length >= lower_bound
                search["lower_bound"] = res.lower_bound
            doc = plan_document(problem.model, res.states, res.rules, problem.goal,
                                cfg.goal_tolerance, cfg.sense, cfg.rule_set, problem.zone,
                                search)
        ctx.cache["plan"] = (res, doc)
    return ctx.cache["plan"]


def best_record(ctx: Any) -> dict[str, Any]:
    res, _ = _outcome(ctx)
    return {"found": res.found, "states": len(res.states), "search_stop": res.stop_reason,
            "expansions": res.expansions, "lower_bound": res.lower_bound}


def finalize(ctx: Any) -> int:
    """plan.json / plan.png / plan.gif and the checker's verdict; exit 1 without a plan."""
    from evomotion.studies.quadruped_plan.views import animate_plan, plot_plan

    cfg = ctx.config.problem
    res, doc = _outcome(ctx)
    ctx.log(f"quadruped-plan {cfg.method} rule set {cfg.rule_set}"
            + (f" function ({cfg.function}) k={constants(cfg)}" if cfg.method == "best-first"
               else "") + f": {res.message}")
    if cfg.method != "best-first" and (cfg.pos_grid, cfg.angle_grid) != (POS_GRID, ANGLE_GRID):
        ctx.log(f"note: least cost and bound hold for the duplicate grid ({cfg.pos_grid:g} "
                f"units, {cfg.angle_grid:g} rad) only; a finer grid can have shorter plans")
    if doc is None:
        return NO_PLAN
    write_plan(ctx.out_dir / "plan.json", doc)
    try:
        summary = check_plan(doc)
        ctx.log(f"checker: ok, {summary['leg_moves']} leg moves over "
                f"{summary['travel']:.2f} units ({summary['leg_moves_per_unit']:.2f} per unit)")
    except PlanViolationError as e:
        ctx.log(f"checker: {e}")
        return NO_PLAN
    plot_plan(doc, ctx.out_dir / "plan.png")
    animate_plan(doc, ctx.out_dir / "plan.gif", max_frames=cfg.gif_max_frames)
    return 0


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
    # steps are batches of expansions; the search's own budgets ([problem]) end it
    defaults={"run": {"generations": 1_000_000, "checkpoint_every": 10}},
    presets={"seed": {"problem": {"method": "best-first", "function": 1, "rule_set": "A"}}},
    preset_notes={"seed": "the seed's first experiment: best-first with its function (1), "
                          "rule set A (the default is function (3), rule set B)"},
    core_algorithms=(),
    algorithms={"search": (SearchConfig, make_driver)},
    finalize=finalize,
    best_record=best_record,
    cli=cli,
    smoke=(
        "algorithm.batch_expansions=40",
        "problem.goal_x=0.0",
        "problem.goal_y=-7.0",
        "problem.start_phi=0.0",
        "problem.gif_max_frames=4",
    ),
)
