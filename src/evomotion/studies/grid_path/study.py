"""The grid-path study (paper 004): descriptor, artifacts and ``evomotion grid-path`` commands.

``evomotion run grid-path --out DIR`` is an ordinary run of the engine (resume, evaluators, stop
rules, stats): the problem supplies the paper's valid initial paths and validity-keeping
mutation, the cellular GA (or the panmictic GA) is stepped one generation (one sweep) at a time.
Besides the engine's files it writes ``path.png`` and the path keys of ``best.json``
(``waypoints``, ``length``, ``valid``, ``optima``, ``gap_percent``). The default is the best
known setting (continuous encoding + repair, synchronous cGA: the exact free optimum on every
bundled map); ``--preset paper`` is the paper's literal one (discrete encoding, line sweep,
pc 0.05, pm 0.01). Exit code 3 when the final path is not valid.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from evomotion.errors import InputError
from evomotion.studies.base import Study
from evomotion.studies.grid_path.maps import random_map, write_map
from evomotion.studies.grid_path.path_result import best_record as path_record
from evomotion.studies.grid_path.path_result import outcome
from evomotion.studies.grid_path.problem import GridPathConfig, GridPathProblem
from evomotion.studies.grid_path.solvers import all_optima
from evomotion.studies.view import StudyView, lazy

NOT_VALID = 3


def make_problem(cfg: GridPathConfig) -> GridPathProblem:
    return GridPathProblem(cfg)


def _result(ctx: Any):
    """The run's path outcome and optima, computed once per context."""
    if "grid-path" not in ctx.cache:
        res = outcome(ctx.problem, ctx.driver, ctx.state, [], ctx.generation, ctx.evaluations,
                      0.0)
        ctx.cache["grid-path"] = (res, all_optima(ctx.problem.map))
    return ctx.cache["grid-path"]


def best_record(ctx: Any) -> dict[str, Any]:
    res, optima = _result(ctx)
    return path_record(res, optima)


def finalize(ctx: Any) -> int:
    """``path.png`` and the one-line summary; exit code 3 when the path is not valid."""
    from evomotion.studies.grid_path.views import save_path_png

    res, optima = _result(ctx)
    problem = ctx.problem
    ends = problem.enc.foot_points()[:, None, :] + np.stack(
        [problem.enc.lower, problem.enc.upper], 1)[..., None] * problem.enc.normal
    save_path_png(problem.map, res.waypoints, optima, ctx.out_dir / "path.png",
                  f"{problem.map.name}: {ctx.config.algorithm.name}, length {res.length:.4f}",
                  perpendiculars=ends)
    gaps = ", ".join(f"{k} {100.0 * (res.length / s.length - 1.0):+.2f}%"
                     for k, s in optima.items())
    ctx.log(f"{problem.map.name}: length {res.length:.4f} valid {res.valid} after "
            f"{ctx.generation} generations; gap to optima: {gaps}")
    return 0 if res.valid else NOT_VALID


cli = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="Grid path planning with a cellular GA (paper 004).")


#: ``study``: runs per row, random maps, population and generations at most
MAX_SEEDS = 1000
MAX_MAPS = 1000
MAX_POP = 100_000
MAX_GENERATIONS = 100_000


@cli.command("make-map")
def make_map(
    out: Annotated[Path, typer.Argument(help="Output .map file (Moving AI format; its folder "
                                             "must exist)")],
    size: Annotated[int, typer.Option(help="Cells per side (2 to 4096)")] = 20,
    density: Annotated[float, typer.Option(help="Fraction of blocked cells, in [0, 1)")] = 0.25,
    seed: Annotated[int, typer.Option(help="Random seed (>= 0)")] = 0,
) -> None:
    """Write a random map whose bottom-left start and top-right goal are connected."""
    from evomotion.core.checks import check_number
    from evomotion.outfile import check_target
    from evomotion.studies.grid_path.problem import MAX_RANDOM_MAP_SIZE

    check_number("--size", size, lo=2, hi=MAX_RANDOM_MAP_SIZE, integer=True)
    check_number("--density", density, lo=0.0, hi=1.0, hi_open=True)
    check_number("--seed", seed, lo=0, integer=True)
    check_target(out, "map file")
    m = random_map(size, density, np.random.default_rng(seed))
    write_map(out, m.blocked)
    typer.echo(f"wrote {out}: {size}x{size}, {int(m.blocked.sum())} blocked cells")


@cli.command("study")
def study(
    experiment: Annotated[str, typer.Option(
        help="paper or beyond ('seed' is the old name of 'paper')")] = "paper",
    seeds: Annotated[int, typer.Option(help="Runs per row (1 to 1000)")] = 30,
    maps: Annotated[list[str] | None, typer.Option(
        "--map", help="Map of the paper experiment (repeatable)")] = None,
    rows: Annotated[list[str] | None, typer.Option("--row", help="Row (repeatable)")] = None,
    pc: Annotated[float, typer.Option(help="Crossover rate in [0, 1] (paper: 0.05)")] = 0.05,
    pm: Annotated[float, typer.Option(
        help="Mutation rate per individual in [0, 1] (paper: 0.01)")] = 0.01,
    generations: Annotated[int, typer.Option(
        help="0: the paper's per map (at most 100000)")] = 0,
    n_maps: Annotated[int, typer.Option(help="beyond: random maps (1 to 1000)")] = 10,
    pop: Annotated[int, typer.Option(help="beyond: population (at most 100000)")] = 100,
    update: Annotated[str, typer.Option(help="beyond: line, sync, fixed, new, uniform")] = "line",
) -> None:
    """Print the experiment table (markdown): success within 1% of the optimum, lengths,
    mean generation of convergence and seconds per run."""
    from evomotion.core.checks import check_choice, check_number
    from evomotion.studies.grid_path import experiments as ex

    if experiment in ex.OLD_EXPERIMENT_NAMES:
        typer.echo(f"note: --experiment {experiment} is the old name of --experiment "
                   f"{ex.OLD_EXPERIMENT_NAMES[experiment]}", err=True)
        experiment = ex.OLD_EXPERIMENT_NAMES[experiment]
    for old in set(rows or []) & set(ex.OLD_ROW_NAMES):
        typer.echo(f"note: --row {old} is the old name of --row {ex.OLD_ROW_NAMES[old]}",
                   err=True)
    rows = [ex.OLD_ROW_NAMES.get(r, r) for r in rows] if rows else rows
    check_choice("--experiment", experiment, ex.EXPERIMENTS)
    check_number("--seeds", seeds, lo=1, hi=MAX_SEEDS, integer=True)
    check_number("--pc", pc, lo=0.0, hi=1.0)
    check_number("--pm", pm, lo=0.0, hi=1.0)
    check_number("--generations", generations, lo=0, hi=MAX_GENERATIONS, integer=True)
    check_number("--n-maps", n_maps, lo=1, hi=MAX_MAPS, integer=True)
    check_number("--pop", pop, lo=1, hi=MAX_POP, integer=True)
    check_choice("--update", update, ex.POLICY_SHORT)
    for name in maps or []:
        if name not in ex.PAPER_MAPS:
            raise InputError(f"--map: unknown {name!r}; available: {', '.join(ex.PAPER_MAPS)}")
    known = ex.PAPER_ROWS if experiment == "paper" else ex.BEYOND_ROWS
    for row in rows or []:
        check_choice("--row", row, known)
    # every optimizer setting checked before the first run
    for row in (rows or ex.PAPER_ROWS) if experiment == "paper" else ():
        for name in maps or list(ex.PAPER_MAPS):
            ex.algorithm_for(row, ex.PAPER_MAPS[name][0], pc, pm).validate()
    if experiment == "beyond":
        ex.algorithm_for(f"cga-L5-{update}", pop, pc, pm).validate()
    literal = " (the paper's literal rates)" if (pc, pm) == (0.05, 0.01) else ""
    if experiment == "paper":
        typer.echo(f"rows: --preset paper (discrete encoding, the paper's m, population and "
                   f"generations per map) with pc {pc:g}, pm {pm:g}{literal}; each row sets "
                   "the neighbourhood and update policy (ga: the panmictic GA)")
    else:
        typer.echo(f"rows: cGA L5 {update}, population {pop}, pc {pc:g}, pm {pm:g}{literal}; "
                   "'paper-encoding' is --preset paper's discrete encoding, the others the "
                   "default's continuous encoding (the default setting is "
                   "'continuous+repair-r5' with --update sync)")
    typer.echo(ex.HEADER)
    if experiment == "paper":
        table = ex.paper_table(seeds, maps or list(ex.PAPER_MAPS), rows or list(ex.PAPER_ROWS),
                               pc, pm, generations)
    else:
        table = ex.beyond_table(seeds, n_maps, rows or list(ex.BEYOND_ROWS), pop,
                                generations or 50, pc, pm, update)
    for result in table:
        typer.echo(result.line())


PAPER_PRESET: dict[str, dict[str, Any]] = {
    "problem": {"mode": "discrete", "m": 1.2, "repair": False},
    "algorithm": {"name": "cga", "pop_size": 100, "neighbourhood": "L5", "update": "line_sweep",
                  "crossover": "one_point", "crossover_rate": 0.05, "mutation_rate": 0.01},
    "run": {"generations": 50},
}

STUDY = Study(
    name="grid-path",
    description="Grid path planning with a cellular GA (paper 004)",
    problem_config=GridPathConfig,
    make_problem=make_problem,
    # best known (docs/grid-path.md, "beyond the paper"): continuous encoding + repair r5 with
    # a synchronous cGA at pc 0.9 / pm 0.2 reaches the exact free optimum (299/300 runs)
    defaults={"algorithm": {"name": "cga", "pop_size": 100, "update": "synchronous",
                            "crossover": "one_point", "crossover_rate": 0.9,
                            "mutation_rate": 0.2},
              "problem": {"mode": "continuous", "m": 1.05, "repair": True,
                          "repair_radius": 5.0},
              "run": {"generations": 50, "history_every": 1}},
    presets={"paper": PAPER_PRESET},
    preset_notes={"paper": "the paper's literal setting: discrete encoding, cGA L5 line sweep, "
                           "pc 0.05, pm 0.01, 100 x 50"},
    core_algorithms=("cga", "ga"),
    finalize=finalize,
    best_record=best_record,
    cli=cli,
    view=StudyView(frames=lazy("evomotion.studies.grid_path.views", "studio_frames")),
    smoke=(
        "algorithm.pop_size=16",
    ),
)
