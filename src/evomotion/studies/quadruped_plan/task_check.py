"""What ``quadruped-plan check`` verifies beyond the plan's own transitions: that the plan
solves its *task*, taken from the world file and the run's configuration, never from the
copies written in the file being checked.

The task comes from ``--world FILE|NAME`` when given, else from the run folder's
``config.toml`` beside the plan (``problem.world``, or ``problem.start_*``/``goal_*`` for a
plan without a world), else from a bundled world of the plan's ``world.name``. Against it:

* the first state is the robot in its nominal stance at the world's start pose;
* the plan's goal is the world's goal, or, for an executed walk, the world's goal moved once
  (``goal_history``: the world's goal from state 0, then one moved goal) by at most the
  documented ``GOAL_MOVE_MAX`` (2 units; the run's ``algorithm.goal_move`` when its
  configuration is at hand); the tolerance is the world's;
* the world the plan was checked in is the world file's: the same bounds and polygons (posts
  that appeared during a walk may be added, from the state where they appeared), the
  clearances and the model of the run's configuration when it is at hand.

The plan is then verified by :func:`.checker.check_plan` with those values put in place, so
a walk that stopped short fails however its ``goal`` field was edited. A plan without a
world and without a run configuration has no task to check against: the verdict says so.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from evomotion.errors import InputError
from evomotion.run.config import config_from_dict, config_from_run_dir
from evomotion.studies.base import Study
from evomotion.studies.quadruped_plan.plans.checker import PlanViolationError
from evomotion.studies.quadruped_plan.rules.model import QuadrupedModel, world_feet
from evomotion.studies.quadruped_plan.worlds.world import World, bundled_worlds, load_world

GOAL_MOVE_MAX = 2.0  # [units] the documented default of algorithm.goal_move
TOL = 1e-6  # [units] / [rad]


@dataclass(frozen=True)
class Task:
    """Start, goal and world a plan must match; ``source`` says where they came from."""

    source: str
    start: tuple[float, float, float]
    goal: tuple[float, float]
    tolerance: float
    goal_move: float = GOAL_MOVE_MAX
    world: World | None = None
    clearances: tuple[float, float] | None = None  # body, foot (None: not known)
    model: dict[str, float] | None = None  # a, b, l_min, l_max, ... (None: not known)


def _run_config(plan_file: Path, study_def: Study) -> Any | None:
    """The configuration of the run folder holding ``plan_file`` (a run of ``study_def``),
    or None."""
    folder = plan_file.parent
    if not (folder / "config.toml").is_file():
        return None
    study, raw = config_from_run_dir(folder)
    if study != study_def.name:
        raise InputError(f"{folder / 'config.toml'}: a run of {study!r}, not of "
                         f"{study_def.name!r}")
    return config_from_dict(study_def, raw)


def find_task(plan_file: Path, doc: dict[str, Any], study_def: Study,
              world: str | None = None) -> Task | None:
    """The task of ``doc`` (read from ``plan_file``; its run folder's configuration is read
    as ``study_def``'s, passed in so that this module needs no import of ``study.py``);
    one-line :class:`InputError` when the plan names a world that cannot be found."""
    cfg = _run_config(plan_file, study_def)
    problem = cfg.problem if cfg is not None else None
    goal_move = GOAL_MOVE_MAX
    clearances = model = None
    if cfg is not None and problem is not None:
        clearances = (problem.body_clearance, problem.foot_clearance)
        model = {k: getattr(problem, k) for k in ("a", "b", "l_min", "l_max",
                                                  "sector_half_width", "min_margin")}
        if cfg.algorithm.name == "receding":
            goal_move = cfg.algorithm.goal_move
    source = world or (problem.world if problem is not None else "")
    if not source and problem is None and doc.get("world"):
        name = str(doc["world"].get("name", ""))
        if name not in bundled_worlds():
            raise InputError(f"{plan_file}: the plan's world {name[:60]!r} is not a bundled "
                             "world; name its file with --world (or check the run folder)")
        source = name
    if source:
        w = load_world(source)
        return Task(f"world {w.source}", w.start, w.goal, w.goal_tolerance, goal_move, w,
                    clearances, model)
    if problem is None:
        return None
    return Task(f"{plan_file.parent / 'config.toml'}", (problem.start_x, problem.start_y,
                problem.start_phi), (problem.goal_x, problem.goal_y), problem.goal_tolerance,
                0.0, None, clearances, model)


def _near(a: list[float], b: tuple[float, ...] | list[float]) -> bool:
    return len(a) == len(b) and all(abs(x - y) <= TOL for x, y in zip(a, b, strict=True))


def _angle_near(a: float, b: float) -> bool:
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi) <= TOL


def apply_task(doc: dict[str, Any], task: Task) -> dict[str, Any]:
    """``doc`` with the task's goal, tolerance and world in place, after checking that the
    plan starts at the task's start and that its goal is the task's (or moved within
    ``task.goal_move``); the first mismatch raises :class:`PlanViolationError`."""
    out = copy.deepcopy(doc)
    src = task.source
    if task.model is not None:
        for k, v in task.model.items():
            if abs(float(doc["model"].get(k, 0.0)) - v) > TOL:
                raise PlanViolationError(f"model.{k} is {doc['model'].get(k)}, the run's "
                                         f"configuration says {v:g}")
    m = doc["model"]
    try:
        model = QuadrupedModel(m["a"], m["b"], m["l_min"], m["l_max"], m["sector_half_width"])
    except ValueError as e:
        raise PlanViolationError(f"model: {e}") from None
    body = doc["states"][0]["body"]
    x, y, phi = task.start
    nominal = model.nominal_state(x, y, phi)
    if not (_near(body[:2], (x, y)) and _angle_near(body[2], phi)) or not all(
            _near(f, g) for f, g in zip(doc["states"][0]["feet"], world_feet(nominal),
                                        strict=True)):
        raise PlanViolationError(f"state 0: the plan does not start at the start of the "
                                 f"{src} (({x:g}, {y:g}) at {math.degrees(phi):g} deg, legs "
                                 "in their nominal stance)")
    _check_goal(doc, task)
    out["goal_tolerance"] = task.tolerance
    if task.world is not None:
        out["world"] = _world(doc, task)
    elif doc.get("world"):
        raise PlanViolationError(f"the plan has a world ({doc['world'].get('name')}), its "
                                 f"task ({src}) has none")
    return out


def _check_goal(doc: dict[str, Any], task: Task) -> None:
    gx, gy = task.goal
    goal = doc["goal"]
    hist = doc.get("goal_history") or [{"goal": goal, "from": 0}]
    if "goal_history" not in doc and not _near(goal, task.goal):
        raise PlanViolationError(f"goal: ({goal[0]:g}, {goal[1]:g}) is not the goal of the "
                                 f"{task.source} ({gx:g}, {gy:g})")
    if not _near(hist[0]["goal"], task.goal) or hist[0]["from"] != 0:
        raise PlanViolationError(f"goal_history[0]: the walk's first goal is not the goal of "
                                 f"the {task.source} ({gx:g}, {gy:g})")
    if len(hist) > 2:
        raise PlanViolationError(f"goal_history: the goal moved {len(hist) - 1} times (at "
                                 "most once)")
    if not _near(goal, hist[-1]["goal"]):
        raise PlanViolationError(f"goal: ({goal[0]:g}, {goal[1]:g}) is not the last goal of "
                                 "goal_history")
    moved = math.hypot(goal[0] - gx, goal[1] - gy)
    if len(hist) == 1 and moved > TOL:
        raise PlanViolationError(f"goal: ({goal[0]:g}, {goal[1]:g}) is not the goal of the "
                                 f"{task.source} ({gx:g}, {gy:g})")
    if moved > task.goal_move + TOL:
        raise PlanViolationError(f"goal: moved {moved:.3f} units from the goal of the "
                                 f"{task.source} ({gx:g}, {gy:g}); a goal moves at most "
                                 f"{task.goal_move:g}")
    if abs(float(doc["goal_tolerance"]) - task.tolerance) > TOL:
        raise PlanViolationError(f"goal_tolerance: {doc['goal_tolerance']:g} written, the "
                                 f"{task.source} says {task.tolerance:g}")


def _world(doc: dict[str, Any], task: Task) -> dict[str, Any]:
    """The world section to check in: the world file's polygons and bounds, the posts the
    plan says appeared (more obstacles only make the check stricter), the run's clearances
    (the plan's where the run's configuration is not at hand)."""
    from evomotion.studies.quadruped_plan.plans.plan import world_section

    mine = doc.get("world")
    if not mine:
        raise PlanViolationError(f"the plan has no world section; its task is the "
                                 f"{task.source}")
    w = task.world
    body, foot = task.clearances or (mine.get("body_clearance", 0.0),
                                     mine.get("foot_clearance", 0.0))
    for key, want in (("body_clearance", body), ("foot_clearance", foot)):
        if float(mine.get(key, 0.0)) < want - TOL:
            raise PlanViolationError(f"world.{key}: {mine.get(key, 0.0):g} written, the run "
                                     f"used {want:g}")
    truth = world_section(w, body, foot)
    if not _near(mine["bounds"], truth["bounds"]):
        raise PlanViolationError(f"world.bounds: {mine['bounds']} are not those of the "
                                 f"{task.source} {truth['bounds']}")
    theirs = [p for p in mine["polygons"] if p.get("from", 0) == 0]
    if len(theirs) != len(truth["polygons"]) or not all(
            p["kind"] == q["kind"] and len(p["points"]) == len(q["points"]) and
            all(_near(a, b) for a, b in zip(p["points"], q["points"], strict=True))
            for p, q in zip(theirs, truth["polygons"], strict=True)):
        raise PlanViolationError(f"world.polygons: the plan's obstacles and no-step zones "
                                 f"are not those of the {task.source}")
    truth["polygons"] += [p for p in mine["polygons"] if p.get("from", 0) > 0]
    return truth
