"""The grid-path study (seed 004): descriptor, artifacts and ``evomotion grid-path`` commands.

``evomotion run grid-path --out DIR`` is an ordinary run of the engine (resume, evaluators, stop
rules, stats): the problem supplies the seed's valid initial paths and validity-keeping
mutation, the cellular GA (or the panmictic GA) is stepped one generation (one sweep) at a time.
Besides the engine's files it writes ``path.png`` and the path keys of ``best.json``
(``waypoints``, ``length``, ``valid``, ``optima``, ``gap_percent``). The default is the best
known setting (continuous encoding + repair, synchronous cGA: the exact free optimum on every
bundled map); ``--preset seed`` is the seed's literal one (discrete encoding, line sweep,
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
from evomotion.studies.grid_path.outcome import best_record as path_record
from evomotion.studies.grid_path.outcome import outcome
from evomotion.studies.grid_path.problem import GridPathConfig, GridPathProblem
from evomotion.studies.grid_path.solvers import all_optima

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
                  help="Grid path planning with a cellular GA (seed 004).")


@cli.command("make-map")
def make_map(
    out: Annotated[Path, typer.Argument(help="Output .map file (Moving AI format)")],
    size: Annotated[int, typer.Option(help="Cells per side")] = 20,
    density: Annotated[float, typer.Option(help="Fraction of blocked cells")] = 0.25,
    seed: Annotated[int, typer.Option(help="Random seed")] = 0,
) -> None:
    """Write a random map whose bottom-left start and top-right goal are connected."""
    m = random_map(size, density, np.random.default_rng(seed))
    write_map(out, m.blocked)
    typer.echo(f"wrote {out}: {size}x{size}, {int(m.blocked.sum())} blocked cells")


@cli.command("study")
def study(
    experiment: Annotated[str, typer.Option(help="seed or beyond")] = "seed",
    seeds: Annotated[int, typer.Option(help="Runs per row")] = 30,
    maps: Annotated[list[str] | None, typer.Option("--map", help="Seed map (repeatable)")] = None,
    rows: Annotated[list[str] | None, typer.Option("--row", help="Row (repeatable)")] = None,
    pc: Annotated[float, typer.Option(help="Crossover rate (seed: 0.05)")] = 0.05,
    pm: Annotated[float, typer.Option(help="Mutation rate per individual (seed: 0.01)")] = 0.01,
    generations: Annotated[int, typer.Option(help="0: the seed's per map")] = 0,
    n_maps: Annotated[int, typer.Option(help="beyond: random maps")] = 10,
    pop: Annotated[int, typer.Option(help="beyond: population")] = 100,
    update: Annotated[str, typer.Option(help="beyond: line, sync, fixed, new, uniform")] = "line",
) -> None:
    """Print the experiment table (markdown): success within 1% of the optimum, lengths,
    mean generation of convergence and seconds per run."""
    from evomotion.studies.grid_path import experiments as ex

    if seeds < 1:
        raise InputError("--seeds: expected >= 1")
    literal = " (the seed's literal rates)" if (pc, pm) == (0.05, 0.01) else ""
    if experiment == "seed":
        typer.echo(f"rows: --preset seed (discrete encoding, the seed's m, population and "
                   f"generations per map) with pc {pc:g}, pm {pm:g}{literal}; each row sets "
                   "the neighbourhood and update policy (ga: the panmictic GA)")
    else:
        typer.echo(f"rows: cGA L5 {update}, population {pop}, pc {pc:g}, pm {pm:g}{literal}; "
                   "'seed-encoding' is --preset seed's discrete encoding, the others the "
                   "default's continuous encoding (the default setting is "
                   "'continuous+repair-r5' with --update sync)")
    typer.echo(ex.HEADER)
    if experiment == "seed":
        for name in maps or []:
            if name not in ex.SEED_MAPS:
                raise InputError(f"--map: unknown {name!r}; available: {', '.join(ex.SEED_MAPS)}")
        table = ex.seed_table(seeds, maps or list(ex.SEED_MAPS), rows or list(ex.SEED_ROWS),
                              pc, pm, generations)
    elif experiment == "beyond":
        if update not in ex.POLICY_SHORT:
            raise InputError(f"--update: expected one of {', '.join(ex.POLICY_SHORT)}")
        table = ex.beyond_table(seeds, n_maps, rows or list(ex.BEYOND_ROWS), pop,
                                generations or 50, pc, pm, update)
    else:
        raise InputError(f"--experiment: expected 'seed' or 'beyond', got {experiment!r}")
    for row in table:
        typer.echo(row.line())


SEED_PRESET = {
    "problem": {"mode": "discrete", "m": 1.2, "repair": False},
    "algorithm": {"name": "cga", "pop_size": 100, "neighbourhood": "L5", "update": "line_sweep",
                  "crossover": "one_point", "crossover_rate": 0.05, "mutation_rate": 0.01},
    "run": {"generations": 50},
}

STUDY = Study(
    name="grid-path",
    description="Grid path planning with a cellular GA (seed 004)",
    problem_config=GridPathConfig,
    make_problem=make_problem,
    # best known (docs/grid-path.md, "beyond the seed"): continuous encoding + repair r5 with
    # a synchronous cGA at pc 0.9 / pm 0.2 reaches the exact free optimum (299/300 runs)
    defaults={"algorithm": {"name": "cga", "pop_size": 100, "update": "synchronous",
                            "crossover": "one_point", "crossover_rate": 0.9,
                            "mutation_rate": 0.2},
              "problem": {"mode": "continuous", "m": 1.05, "repair": True,
                          "repair_radius": 5.0},
              "run": {"generations": 50, "history_every": 1}},
    presets={"seed": SEED_PRESET},
    preset_notes={"seed": "the seed's literal setting: discrete encoding, cGA L5 line sweep, "
                          "pc 0.05, pm 0.01, 100 x 50"},
    core_algorithms=("cga", "ga"),
    finalize=finalize,
    best_record=best_record,
    cli=cli,
    smoke=(
        "algorithm.pop_size=16",
    ),
)
