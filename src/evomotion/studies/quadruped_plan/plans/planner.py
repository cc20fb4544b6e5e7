"""The task (``[problem]``) and one planning run: build the search problem, search it.

The task is the walk to plan: start, goal, rule set, the robot's geometry, the world and
the duplicate-detection grids (they define which states are the same). How it is searched
(method, evaluation function, budgets) is ``[algorithm]``, :class:`.search_config.
SearchConfig`; :func:`solve` takes both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from evomotion.core.checks import check_fields, check_number
from evomotion.core.search import SearchResult
from evomotion.errors import FileFormatError, InputError
from evomotion.sim.quadruped.geometry import BODY_A, BODY_B, L_MAX, L_MIN, SECTOR_HALF_WIDTH
from evomotion.studies.quadruped_plan.plans.search_config import SearchConfig
from evomotion.studies.quadruped_plan.plans.walk_search import walk_astar, walk_best_first
from evomotion.studies.quadruped_plan.rules.evaluation import (
    PAPER_CONSTANTS,
    paper_evaluation,
)
from evomotion.studies.quadruped_plan.rules.heuristic import plan_length_heuristic
from evomotion.studies.quadruped_plan.rules.model import QuadrupedModel
from evomotion.studies.quadruped_plan.rules.rules import (
    ANGLE_GRID,
    POS_GRID,
    ExclusionZone,
    WalkProblem,
)
from evomotion.studies.quadruped_plan.worlds.terrain import Terrain, check_world_task
from evomotion.studies.quadruped_plan.worlds.world import World, load_world

#: the largest magnitude of a coordinate or constant; the longest body side or leg; the most
#: GIF frames (each ~1 MB while the GIF is made)
MAX_COORD = 1e6
MAX_BODY = 100.0  # [units]
MAX_GIF_FRAMES = 400


@dataclass(frozen=True)
class QuadrupedPlanConfig:
    """The ``[problem]`` section, the task. Lengths in the paper's units, angles in radians.

    ``zone_radius`` > 0 adds an exclusion zone (body centre and feet stay out of it).
    ``sense``: walking direction, -1 = body -Y (default, see docs), +1 = +Y, 0 = either.
    ``pos_grid`` [units] / ``angle_grid`` [rad]: the duplicate-detection grids (docs); they
    stay here, not in ``[algorithm]``, because they define the state space (which states are
    the same). Coordinates are at most ``MAX_COORD`` in magnitude. ``world``: start, goal
    and tolerance come from the world file (``start_*``/``goal_*``/``goal_tolerance`` must
    then stay unset), and plans keep ``body_clearance`` / ``foot_clearance`` from its
    obstacles and no-step zones. The search settings are ``[algorithm]``
    (:class:`~.search_config.SearchConfig`).
    """

    start_x: float = 0.0
    start_y: float = 0.0
    start_phi: float = 1.5 * math.pi
    goal_x: float = -10.0
    goal_y: float = 10.0
    goal_tolerance: float = 0.25
    rule_set: str = "B"
    pos_grid: float = POS_GRID
    angle_grid: float = ANGLE_GRID
    sense: int = -1
    a: float = BODY_A  # the robot's geometry (sim/quadruped/geometry.py)
    b: float = BODY_B
    l_min: float = L_MIN
    l_max: float = L_MAX
    sector_half_width: float = SECTOR_HALF_WIDTH
    min_margin: float = 0.0
    zone_x: float = 0.0
    zone_y: float = 0.0
    zone_radius: float = 0.0
    world: str = ""  # a bundled world (corridor, field, gaps) or a .world file; "" = none
    body_clearance: float = 0.05  # [units] least body-obstacle distance in a world
    foot_clearance: float = 0.05  # [units] least foot distance to no-step zones, obstacles
    shifts: bool = False  # add the body shifts, rules 28-31 (beyond the paper; docs)
    gif_max_frames: int = 150

    def validate(self) -> None:
        """One-line :class:`InputError` for impossible settings (see :func:`validate`)."""
        validate(self)


def validate(cfg: QuadrupedPlanConfig) -> None:
    check_fields(cfg, "problem")
    for key in ("start_x", "start_y", "start_phi", "goal_x", "goal_y", "zone_x", "zone_y",
                "goal_tolerance", "zone_radius", "a", "b", "l_min", "l_max", "min_margin"):
        check_number(f"problem.{key}", getattr(cfg, key), lo=-MAX_COORD, hi=MAX_COORD)
    for key in ("a", "b", "l_min", "l_max"):
        check_number(f"problem.{key}", getattr(cfg, key), lo=-MAX_COORD, hi=MAX_BODY)
    check_number("problem.pos_grid", cfg.pos_grid, lo=1e-4, hi=MAX_BODY)
    check_number("problem.angle_grid", cfg.angle_grid, lo=1e-6, hi=math.pi)
    check_number("problem.zone_radius", cfg.zone_radius, lo=0.0)
    check_number("problem.min_margin", cfg.min_margin, lo=0.0)
    check_number("problem.gif_max_frames", cfg.gif_max_frames, lo=1, hi=MAX_GIF_FRAMES,
                 integer=True)
    if cfg.rule_set not in ("A", "B"):
        raise InputError(f"problem.rule_set: expected 'A' or 'B', got {cfg.rule_set!r}")
    if cfg.sense not in (-1, 0, 1):
        raise InputError(f"problem.sense: expected -1, 0 or 1, got {cfg.sense}")
    if cfg.pos_grid <= 0 or cfg.angle_grid <= 0:
        raise InputError("problem.pos_grid and problem.angle_grid: expected > 0")
    try:
        make_model(cfg)
    except InputError as e:
        raise InputError(f"{e} (problem.a, b, l_min, l_max, sector_half_width, "
                         "min_margin)") from None
    if cfg.goal_tolerance <= 0:
        raise InputError("problem.goal_tolerance: expected > 0")
    if not isinstance(cfg.shifts, bool):
        raise InputError(f"problem.shifts: expected true or false, got {cfg.shifts!r}")
    if cfg.shifts and cfg.sense == 0:
        raise InputError("problem.shifts: body shifts need problem.sense = -1 or 1")
    check_number("problem.body_clearance", cfg.body_clearance, lo=0.0, hi=100.0)
    check_number("problem.foot_clearance", cfg.foot_clearance, lo=0.0, hi=100.0)
    if cfg.world:
        base = QuadrupedPlanConfig()
        given = [k for k in ("start_x", "start_y", "start_phi", "goal_x", "goal_y",
                             "goal_tolerance", "zone_radius")
                 if getattr(cfg, k) != getattr(base, k)]
        if given:
            raise InputError(f"problem.{given[0]}: the world file gives start, goal and "
                             "obstacles; unset it or remove problem.world")


def make_model(cfg: QuadrupedPlanConfig) -> QuadrupedModel:
    try:
        return QuadrupedModel(a=cfg.a, b=cfg.b, l_min=cfg.l_min, l_max=cfg.l_max,
                              sector_half_width=cfg.sector_half_width,
                              min_margin=cfg.min_margin)
    except ValueError as e:
        raise InputError(f"problem: {e}") from None


def make_zone(cfg: QuadrupedPlanConfig) -> ExclusionZone | None:
    return ExclusionZone(cfg.zone_x, cfg.zone_y, cfg.zone_radius) if cfg.zone_radius > 0 \
        else None


def load_config_world(cfg: QuadrupedPlanConfig) -> World | None:
    return load_world(cfg.world) if cfg.world else None


def with_world(cfg: QuadrupedPlanConfig) -> tuple[QuadrupedPlanConfig, World | None]:
    """``cfg`` with the world's start and goal filled in (and the world)."""
    world = load_config_world(cfg)
    if world is None:
        return cfg, None
    (sx, sy, sphi), (gx, gy) = world.start, world.goal
    return replace(cfg, start_x=sx, start_y=sy, start_phi=sphi, goal_x=gx, goal_y=gy,
                   goal_tolerance=world.goal_tolerance), world


def make_problem(cfg: QuadrupedPlanConfig) -> WalkProblem:
    """The search problem: start with the legs in their nominal positions (from the world's
    start, with its obstacles and no-step zones, when ``problem.world`` is set)."""
    validate(cfg)
    cfg, world = with_world(cfg)
    model = make_model(cfg)
    zone = make_zone(cfg)
    if zone is not None and zone.contains(cfg.start_x, cfg.start_y):
        raise InputError("problem.zone_*: the start lies inside the exclusion zone")
    start = model.nominal_state(cfg.start_x, cfg.start_y, cfg.start_phi)
    terrain = None
    if world is not None:
        check_world_task(world, model, cfg.body_clearance, cfg.foot_clearance)
        terrain = Terrain(world, model, None, cfg.body_clearance, cfg.foot_clearance)
        why = terrain.stance_problem(start)
        if why is not None:
            raise FileFormatError(world.source, world.start_line, "start: the robot cannot "
                                  f"stand there in its nominal stance ({why})")
    return WalkProblem(model, start, (cfg.goal_x, cfg.goal_y), cfg.rule_set,
                       cfg.goal_tolerance, cfg.sense, zone, cfg.pos_grid, cfg.angle_grid,
                       terrain, shifts=cfg.shifts)


def unreachable_reason(cfg: QuadrupedPlanConfig) -> str | None:
    """A reason known before searching that no plan exists, else None."""
    zone = make_zone(cfg)
    if zone is not None and math.hypot(cfg.goal_x - zone.x, cfg.goal_y - zone.y) + \
            cfg.goal_tolerance <= zone.radius:
        return (f"no plan: the goal ({cfg.goal_x:g}, {cfg.goal_y:g}) lies inside the "
                f"exclusion zone (centre ({zone.x:g}, {zone.y:g}), radius {zone.radius:g}), "
                "which the body may not enter")
    return None


def solve(task: QuadrupedPlanConfig, search: SearchConfig | None = None,
          problem: WalkProblem | None = None, max_seconds: float | None = None
          ) -> SearchResult:
    """Run the ``search`` (default: :class:`SearchConfig`'s) on ``problem`` (built from
    ``task`` when None)."""
    search = search or SearchConfig()
    search.validate()
    problem = problem or make_problem(task)
    secs = search.max_seconds if max_seconds is None else max_seconds
    if search.method == "best-first":
        ev = paper_evaluation(search.function, search.constants(task.rule_set), problem.goal,
                              task.sense)
        return walk_best_first(problem, ev, search.max_expansions, secs)
    h = plan_length_heuristic(problem.model, problem.goal, problem.goal_tolerance,
                              task.sense, search.heuristic_gain, problem.shifts)
    weight = 1.0 if search.method == "astar" else search.weight
    return exact_plan(problem, walk_astar(problem, h, weight, search.max_expansions, secs))


def exact_plan(problem: WalkProblem, res: SearchResult) -> SearchResult:
    """With a non-default duplicate grid, the found plan replayed exactly (see :func:`replay`)."""
    if res.found and (problem.pos_grid, problem.angle_grid) != (POS_GRID, ANGLE_GRID):
        exact = replay(problem, res.rules)
        if exact is not None:
            res.states, res.rules = exact
            res.cost = float(len(exact[0]) - 1)
    return res


def replay(problem: WalkProblem, rules: list, finish_expansions: int = 50_000
           ) -> tuple[list[tuple], list] | None:
    """The plan's rules applied exactly from the start, as ``(states, rules)``.

    With a coarse duplicate grid a node stores one state of its cell, and a node re-parented
    onto a cheaper path keeps children made from its earlier state, so the traced states can
    disagree with the rules by up to a grid cell; the replayed states are the exact ones. If
    a rule is not applicable there or the replayed end misses the goal, a fine-grid weighted A*
    (w = 3), else the paper's best-first with function (3) (each at most ``finish_expansions``)
    finishes the plan from the last exact state (or from 4, 8, 16, 32 states earlier when
    that fails), which can make it longer; None if all fail."""
    s = problem.start()
    states, out_rules = [s], [rules[0]]
    for rule in rules[1:]:
        nxt = next((c for r, c, _ in problem.successors(s) if r == rule), None)
        if nxt is None:
            break
        s = nxt
        states.append(s)
        out_rules.append(rule)
    if problem.is_goal(s):
        return states, out_rules
    h = plan_length_heuristic(problem.model, problem.goal, problem.goal_tolerance,
                              problem.sense, "sampled", problem.shifts)
    ev = paper_evaluation(3, PAPER_CONSTANTS[(3, problem.rule_set)], problem.goal, problem.sense)
    n = len(states)
    for cut in sorted({max(1, n - back) for back in (0, 4, 8, 16, 32)}, reverse=True):
        rest = WalkProblem(problem.model, states[cut - 1][:11], problem.goal,
                           problem.rule_set, problem.goal_tolerance, problem.sense,
                           problem.zone, terrain=problem.terrain, shifts=problem.shifts)
        tail = walk_astar(rest, h, 3.0, finish_expansions)
        if not tail.found:  # the paper's best-first search with its function (3)
            tail = walk_best_first(rest, ev, finish_expansions)
        if tail.found:
            return (states[:cut] + list(tail.states[1:]),
                    out_rules[:cut] + list(tail.rules[1:]))
    return None
