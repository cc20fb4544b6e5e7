"""Study ``quadruped-plan``: quadruped walking plans by best-first / A* search (paper 003).

``evomotion run quadruped-plan`` searches one plan through the run loop (``[problem]`` =
QuadrupedPlanConfig, the task; ``[algorithm]`` = SearchConfig, the method and budgets of the
search stepped in batches of expansions, see :mod:`.search_driver`; the search keys' old places
``problem.method`` etc. are still read, ``moved_keys``): stats.csv per batch, checkpoints,
resume; at the end ``plan.json``, ``plan.png``, ``plan.gif`` and the checker's verdict in
``log.txt``. ``evomotion quadruped-plan study`` prints the paper's 12-configuration table;
``evomotion quadruped-plan check PLAN.json`` re-verifies a plan (exit 1 on a violation). Exit
codes: 0 plan found; 1 no plan (unreachable goal, budget spent) or a violation.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import typer

from evomotion.errors import InputError
from evomotion.outfile import check_target, write_json
from evomotion.studies.base import Study
from evomotion.studies.quadruped_plan.missions.driver import RecedingConfig
from evomotion.studies.quadruped_plan.missions.driver import make_driver as make_receding_driver
from evomotion.studies.quadruped_plan.plans.checker import PlanViolationError, check_plan
from evomotion.studies.quadruped_plan.plans.experiment import format_table, paper_table
from evomotion.studies.quadruped_plan.plans.plan import (
    plan_document,
    read_plan,
    world_section,
    write_plan,
)
from evomotion.studies.quadruped_plan.plans.planner import (
    QuadrupedPlanConfig,
    exact_plan,
    make_problem,
)
from evomotion.studies.quadruped_plan.plans.search_config import SEARCH_KEYS, SearchConfig
from evomotion.studies.quadruped_plan.plans.search_driver import make_driver
from evomotion.studies.quadruped_plan.rules.rules import ANGLE_GRID, POS_GRID
from evomotion.studies.quadruped_plan.task_check import apply_task, find_task
from evomotion.studies.view import StudyView, lazy

NO_PLAN = 1


def _outcome(ctx: Any) -> tuple[Any, dict | None]:
    """The search result (exact plan) and its plan document, computed once per context."""
    if "plan" not in ctx.cache:
        cfg, alg, problem = ctx.config.problem, ctx.config.algorithm, ctx.problem
        res = exact_plan(problem, ctx.driver.result(ctx.state))
        doc = None
        if res.found:
            search = {"method": alg.method, "function": alg.function,
                      "k": list(alg.constants(cfg.rule_set)), "weight": alg.weight,
                      "stop_reason": res.stop_reason, "expansions": res.expansions,
                      "generated": res.generated, "reopened": res.reopened,
                      "seconds": res.seconds, "cost": res.cost, "pos_grid": cfg.pos_grid,
                      "angle_grid": cfg.angle_grid}
            if alg.method != "best-first":  # proved: least plan length >= lower_bound
                search["lower_bound"] = res.lower_bound
            world = None
            if problem.terrain is not None:
                world = world_section(problem.terrain.world, cfg.body_clearance,
                                      cfg.foot_clearance)
            doc = plan_document(problem.model, res.states, res.rules, problem.goal,
                                problem.goal_tolerance, cfg.sense, cfg.rule_set, problem.zone,
                                search, world)
            doc["shifts"] = problem.shifts
        ctx.cache["plan"] = (res, doc)
    return ctx.cache["plan"]


def _receding(ctx: Any) -> bool:
    return ctx.config.algorithm.name == "receding"


def best_record(ctx: Any) -> dict[str, Any]:
    if _receding(ctx):
        from evomotion.studies.quadruped_plan.missions.mission import summary

        return summary(ctx.state)
    res, _ = _outcome(ctx)
    return {"found": res.found, "states": len(res.states), "search_stop": res.stop_reason,
            "expansions": res.expansions, "lower_bound": res.lower_bound}


def finalize(ctx: Any) -> int:
    """plan.json / plan.png / plan.gif and the checker's verdict; exit 1 without a plan."""
    from evomotion.studies.quadruped_plan.views import animate_plan, plot_plan

    cfg, alg = ctx.config.problem, ctx.config.algorithm
    if _receding(ctx):
        return _finalize_mission(ctx)
    res, doc = _outcome(ctx)
    ctx.log(f"quadruped-plan {alg.method} rule set {cfg.rule_set}"
            + (f" function ({alg.function}) k={alg.constants(cfg.rule_set)}"
               if alg.method == "best-first" else "") + f": {res.message}")
    if alg.method != "best-first" and (cfg.pos_grid, cfg.angle_grid) != (POS_GRID, ANGLE_GRID):
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


def _finalize_mission(ctx: Any) -> int:
    """mission.json (the executed walk), its pictures and the checker's verdict."""
    from evomotion.studies.quadruped_plan.missions.doc import mission_document
    from evomotion.studies.quadruped_plan.missions.mission import summary
    from evomotion.studies.quadruped_plan.views import animate_plan, plot_plan

    mission, state = ctx.driver.mission, ctx.state
    doc = mission_document(mission, state)
    write_plan(ctx.out_dir / "mission.json", doc)
    s = summary(state)
    ctx.log(f"receding-horizon walk in {mission.world.name}: {state.done or 'unfinished'}; "
            f"{s['transitions']} transitions, {s['replans']} replans, planning "
            f"{s['plan_ms_median']:.1f} ms median / {s['plan_ms_max']:.1f} ms max per replan, "
            f"{s['events']} disturbances")
    if s["time_bound_replans"]:
        ctx.log(f"note: {s['time_bound_replans']} replans were cut by algorithm.replan_ms: "
                "this walk depends on the machine's speed and is not reproducible")
    ok = True
    try:
        check_plan(doc)
        ctx.log("checker: ok, every executed state, rule and disturbance verified")
    except PlanViolationError as e:
        if state.done == "reached":
            ctx.log(f"checker: {e}")
            ok = False
        else:  # an unfinished walk does not end at the goal; everything else must hold
            ctx.log(f"checker (walk not finished): {e}")
    plot_plan(doc, ctx.out_dir / "plan.png")
    animate_plan(doc, ctx.out_dir / "plan.gif", max_frames=ctx.config.problem.gif_max_frames)
    return 0 if state.done == "reached" and ok else NO_PLAN


cli = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="Quadruped walking plans by best-first / A* search (paper 003).")


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
    """Print the paper's 12-configuration table next to the paper's figures."""
    from evomotion.core.checks import check_number

    check_number("--astar-pos-grid", astar_pos_grid, lo=0.0, lo_open=True)
    check_number("--astar-angle-grid", astar_angle_grid, lo=0.0, lo_open=True)
    check_number("--astar-seconds", astar_seconds, lo=0.0, lo_open=True, hi=3600.0)
    check_number("--max-expansions", max_expansions, lo=1, hi=10**9, integer=True)
    rows = paper_table(search=SearchConfig(max_expansions=max_expansions), astar_rows=astar,
                       astar_seconds=astar_seconds, astar_grid=(astar_pos_grid, astar_angle_grid))
    typer.echo(format_table(rows))
    if any(r.stop_reason == "found" and r.check != "ok" for r in rows):
        raise typer.Exit(1)


@cli.command("missions")
def missions_cmd(
    seeds: Annotated[int, typer.Option(help="Disturbance seeds per world and setting")] = 20,
    worlds: Annotated[str, typer.Option(help="Comma-separated worlds")] = "corridor,gaps,field",
    rule_sets: Annotated[str, typer.Option(help="Rule sets, e.g. AB")] = "AB",
    heuristics: Annotated[str, typer.Option(
        help="ARA* heuristic gains: analytic,sampled")] = "analytic,sampled",
    shifts: Annotated[bool, typer.Option(help="Add the body shifts (rules 28-31)")] = False,
    json_out: Annotated[Path | None, typer.Option("--json", help="Write the figures here")] = None,
) -> None:
    """Receding-horizon walks vs one-shot plans in the bundled worlds (docs)."""

    from evomotion.studies.quadruped_plan.missions.experiment import format_rows, run_row
    from evomotion.studies.quadruped_plan.rules.heuristic import GAINS
    from evomotion.studies.quadruped_plan.worlds.world import load_world

    if not 1 <= seeds <= 10_000:
        raise InputError(f"--seeds: expected 1 to 10000, got {seeds}")
    if json_out is not None:
        check_target(json_out, "figures file")
    names = [w.strip() for w in worlds.split(",") if w.strip()]
    if not names:
        raise InputError(f"--worlds: expected one or more comma-separated worlds, got "
                         f"{worlds!r}")
    for name in names:
        load_world(name)
    if not rule_sets or any(r not in "AB" for r in rule_sets):
        raise InputError(f"--rule-sets: expected letters A and/or B, got {rule_sets!r}")
    gains = [h.strip() for h in heuristics.split(",") if h.strip()]
    bad = [h for h in gains if h not in GAINS]
    if bad or not gains:
        raise InputError(f"--heuristics: expected some of {', '.join(GAINS)}, got {heuristics!r}")
    rows = []
    for name in names:
        for rs in rule_sets:
            for gain in gains:
                rows.append(run_row(name, rs, gain, seeds, shifts))
                typer.echo(format_rows(rows[-1:]).splitlines()[-1])
    typer.echo(format_rows(rows))
    if json_out is not None:
        write_json(json_out, [r.figures() for r in rows], "figures file", indent=1)
    if any(r.check_failures for r in rows):
        for r in rows:
            for line in r.check_failures:
                typer.echo(f"checker: {r.world} {r.rule_set}: {line}")
        raise typer.Exit(1)


@cli.command("simulate")
def simulate_cmd(
    plan: Annotated[Path, typer.Argument(help="plan.json / mission.json or a run folder")],
    video: Annotated[Path | None, typer.Option(help="Also write an MP4 of the execution")] = None,
    speed: Annotated[float, typer.Option(help="Video speed-up over real time")] = 8.0,
    json_out: Annotated[bool, typer.Option("--json", help="Print the result as JSON")] = False,
) -> None:
    """Execute a plan on the simulated MuJoCo quadruped (exit 1 if the body falls)."""
    import json

    from evomotion.sim.render import RenderUnavailableError
    from evomotion.studies.quadruped_plan.plans.simulate import simulate_document

    if not 0.1 <= speed <= 1000:
        raise InputError(f"--speed: expected 0.1 to 1000, got {speed}")
    if video is not None:
        check_target(video, "video")  # before a minute of simulation, not after
    path = plan_path(plan)
    doc = read_plan(path)
    try:
        out = simulate_document(doc, video, speed, source=path)
    except RenderUnavailableError as e:
        raise InputError(f"--video: {e}") from None
    if json_out:
        typer.echo(json.dumps(out, indent=1))
    else:
        typer.echo(f"{plan}: {out['message'] or ('body up' if out['body_up'] else 'fell')}; "
                   f"least support margin {_mm(out['min_support_margin_m'])}, final error "
                   f"{_mm(out['final_position_error_m'])} / "
                   f"{math.degrees(out['final_heading_error_rad'] or 0):.1f} deg, "
                   f"{out['duration_s']:.0f} s simulated in {out['wall_seconds']:.1f} s")
    if not out["body_up"]:
        raise typer.Exit(1)


def _mm(v: float | None) -> str:
    return "n/a" if v is None else f"{1000 * v:.1f} mm"


@cli.command("check")
def check_cmd(
    plan: Annotated[Path, typer.Argument(
        help="plan.json / mission.json, or a run folder holding one")],
    world: Annotated[str | None, typer.Option(
        help="The world file (or bundled name) the plan must solve; default: the run "
             "folder's problem.world, else the plan's bundled world")] = None,
) -> None:
    """Re-verify every state and transition of a plan, and that it goes from the world's
    start to the world's goal; exit 1 on the first violation."""
    plan = plan_path(plan)
    doc = read_plan(plan)
    task = find_task(plan, doc, STUDY, world)
    try:
        if task is not None:
            doc = apply_task(doc, task)
        summary = check_plan(doc)
    except PlanViolationError as e:
        typer.echo(f"{plan}: {e}")
        raise typer.Exit(1) from None
    against = f"against the {task.source}" if task is not None else \
        "(start and goal as written: no world and no run configuration to check them against)"
    typer.echo(f"{plan}: ok, {summary['states']} states, {summary['leg_moves']} leg moves, "
               f"{summary['travel']:.2f} units travelled, {against}")


def plan_path(path: Path) -> Path:
    """A plan file, or the plan.json / mission.json of a run folder (one-line errors)."""
    if not path.is_dir():
        return path
    found = [path / n for n in ("mission.json", "plan.json") if (path / n).is_file()]
    if not found:
        raise InputError(f"{path}: expected a plan file or a run folder with plan.json or "
                         "mission.json (a run that found no plan has none)")
    return found[0]


STUDY = Study(
    name="quadruped-plan",
    description="Quadruped walking plans by best-first / A* search (paper 003).",
    problem_config=QuadrupedPlanConfig,
    make_problem=make_problem,
    # steps are batches of expansions; the search's own budgets ([algorithm]) end it
    defaults={"run": {"generations": 1_000_000, "checkpoint_every": 10}},
    presets={"paper": {"algorithm": {"method": "best-first", "function": 1},
                       "problem": {"rule_set": "A"}}},
    preset_notes={"paper": "the paper's first experiment: best-first with its function (1), "
                           "rule set A (the default is function (3), rule set B)"},
    core_algorithms=(),
    algorithms={"search": (SearchConfig, make_driver),
                "receding": (RecedingConfig, make_receding_driver)},
    finalize=finalize,
    best_record=best_record,
    cli=cli,
    view=StudyView(frames=lazy("evomotion.studies.quadruped_plan.views",
                                          "studio_frames")),
    # the search settings were [problem] keys before issue 32 (receding: heuristic_gain only)
    moved_keys={f"problem.{k}": f"algorithm.{k}" for k in SEARCH_KEYS},
    smoke=(
        "algorithm.batch_expansions=40",
        "problem.goal_x=0.0",
        "problem.goal_y=-7.0",
        "problem.start_phi=0.0",
        "problem.gif_max_frames=4",
    ),
)
