"""The receding-horizon walker as a driver of the run loop (``algorithm.name = "receding"``).

One step is one replan and its execution (:meth:`.mission.Mission.step`); the state is the
plain :class:`.mission.MissionState`, checkpointed as JSON (floats round-trip exactly), and
every random draw comes from the run's generator, so a run resumes bit-identically and one
seed gives one walk. ``stats.csv`` counts expansions as evaluations; ``best`` is the
distance to the goal after the step, then ``transitions``, ``replans``, ``plan_ms`` (this
replan), ``events`` (landing errors, slips, obstacles in view, goal moves so far).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields, replace
from typing import Any

import numpy as np

from evomotion.core.checks import check_fields, check_number
from evomotion.core.problem import Sense
from evomotion.errors import InputError
from evomotion.run.driver import Driver, Evaluate, StepReport
from evomotion.studies.quadruped_plan.missions.mission import (
    PLANNERS,
    Disturbances,
    Mission,
    MissionState,
    ReplanSettings,
)
from evomotion.studies.quadruped_plan.plans.plan import MAX_STATES
from evomotion.studies.quadruped_plan.rules.heuristic import GAINS

EXTRA_COLUMNS = ("transitions", "replans", "plan_ms", "events")
MAX_TRANSITIONS = MAX_STATES - 4  # the last rule adds a landing error and a slip


@dataclass(frozen=True)
class RecedingConfig:
    """``[algorithm]`` of a receding-horizon walk (see :mod:`.mission` for each field;
    ``heuristic_gain``: the ARA* heuristic's rotation bound, ``problem.heuristic_gain`` before
    issue 32)."""

    name: str = "receding"
    planner: str = "anytime"  # "anytime" (the paper's best-first (3), then ARA*) or "best-first"
    heuristic_gain: str = "analytic"
    horizon: int = 8
    replan_expansions: int = 800
    replan_ms: float = 2000.0
    lookahead: float = 5.0
    waypoint_tolerance: float = 1.0
    max_transitions: int = 2_000
    max_replans: int = 400
    progress_transitions: int = 100
    escalation: int = 10
    foot_noise: float = 0.05
    slip_probability: float = 0.03
    slip_max: float = 0.3
    appear_probability: float = 0.0
    goal_move: float = 2.0

    def validate(self) -> None:
        check_fields(self, "algorithm")
        if self.planner not in PLANNERS:
            raise InputError(f"algorithm.planner: expected one of {', '.join(PLANNERS)}, "
                             f"got {self.planner!r}")
        if self.heuristic_gain not in GAINS:
            raise InputError(f"algorithm.heuristic_gain: expected one of {', '.join(GAINS)}, "
                             f"got {self.heuristic_gain!r}")
        for key in ("horizon", "replan_expansions", "max_replans"):
            check_number(f"algorithm.{key}", getattr(self, key), lo=1, hi=10_000_000,
                         integer=True)
        # a walk stops at max_transitions states (+ the last rule's landing error and slip):
        # mission.json stays within what plan.json readers accept
        check_number("algorithm.max_transitions", self.max_transitions, lo=1,
                     hi=MAX_TRANSITIONS, integer=True)
        check_number("algorithm.progress_transitions", self.progress_transitions, lo=0,
                     hi=1_000_000, integer=True)
        check_number("algorithm.escalation", self.escalation, lo=1, hi=100, integer=True)
        check_number("algorithm.replan_ms", self.replan_ms, lo=1e-3, hi=1e7)
        for key in ("lookahead", "waypoint_tolerance"):
            check_number(f"algorithm.{key}", getattr(self, key), lo=1e-3, hi=1e4)
        for key in ("foot_noise", "slip_max", "goal_move"):
            check_number(f"algorithm.{key}", getattr(self, key), lo=0.0, hi=1e3)
        for key in ("slip_probability", "appear_probability"):
            check_number(f"algorithm.{key}", getattr(self, key), lo=0.0, hi=1.0)

    def settings(self) -> ReplanSettings:
        return ReplanSettings(**{f.name: getattr(self, f.name) for f in fields(ReplanSettings)})

    def disturbances(self) -> Disturbances:
        return Disturbances(**{f.name: getattr(self, f.name) for f in fields(Disturbances)})


def _to_json(state: MissionState) -> dict[str, Any]:
    d = asdict(state)
    d["bounds"] = [None if math.isinf(b) else b for b in state.bounds]
    d["progress_best"] = state.progress_best if math.isfinite(state.progress_best) else None
    return d


def _from_json(meta: dict[str, Any]) -> MissionState:
    spawned = tuple((v, int(i)) for v, i in meta["spawned"])
    return MissionState(
        real=tuple(meta["real"]), goal=tuple(meta["goal"]), path=tuple(meta["path"]),
        revealed=tuple(meta["revealed"]), spawned=spawned, replans=int(meta["replans"]),
        plan_ms=tuple(meta["plan_ms"]), expansions=int(meta["expansions"]),
        bounds=tuple(math.inf if b is None else b for b in meta["bounds"]),
        goal_moved_at=int(meta["goal_moved_at"]), idle=int(meta["idle"]),
        route_length=float(meta["route_length"]), done=meta["done"],
        time_bound=int(meta["time_bound"]),
        progress_best=math.inf if meta.get("progress_best") is None
        else float(meta["progress_best"]), stalled=int(meta.get("stalled", 0)),
        escalated=bool(meta.get("escalated", False)))


class RecedingDriver(Driver):
    sense: Sense = "min"
    extra_columns = EXTRA_COLUMNS
    uses_evaluator = False
    snapshot_every_step = True

    def __init__(self, mission: Mission) -> None:
        self.mission = mission

    def init(self, rng: np.random.Generator) -> MissionState:
        return self.mission.start()

    def step(self, state: MissionState, rng: np.random.Generator,
             evaluate: Evaluate) -> tuple[MissionState, StepReport]:
        before = state.expansions
        state = self.mission.step(state, rng)
        dist = math.hypot(state.real[0] - state.goal[0], state.real[1] - state.goal[1])
        transitions = sum(1 for p in state.path if p["rule"] > 0)
        extras = {"transitions": transitions, "replans": state.replans,
                  "plan_ms": round(state.plan_ms[-1], 3),
                  "events": sum(1 for p in state.path if p["event"] not in ("", "start"))}
        lines = [] if not state.done else [f"mission: {state.done} after {transitions} "
                                           f"transitions and {state.replans} replans"]
        return state, StepReport(state.expansions - before, np.array([dist]), extras=extras,
                                 lines=lines)

    def stop(self, state: MissionState) -> str | None:
        if not state.done:
            return None
        return "reached" if state.done == "reached" else "failed"

    def best(self, state: MissionState) -> tuple[np.ndarray, float]:
        if state.done != "reached":
            return np.zeros(0), math.inf
        return np.zeros(0), float(sum(1 for p in state.path if p["rule"] > 0))

    def state_type(self) -> type:
        return MissionState

    def state_arrays(self, state: MissionState) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        return {}, _to_json(state)

    def restore(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> MissionState:
        return _from_json(meta)


def make_mission(problem_cfg: Any, algo: RecedingConfig) -> Mission:
    from evomotion.studies.quadruped_plan.plans.planner import load_config_world, make_model

    algo.validate()
    world = load_config_world(problem_cfg)
    if world is None:
        raise InputError("algorithm.name = 'receding' needs a world: set problem.world to "
                         "corridor, field, gaps or a .world file")
    return Mission(world, make_model(problem_cfg), problem_cfg.rule_set, problem_cfg.sense,
                   algo.heuristic_gain, algo.settings(), algo.disturbances(),
                   planner=algo.planner, body_clearance=problem_cfg.body_clearance,
                   foot_clearance=problem_cfg.foot_clearance, shifts=problem_cfg.shifts)


def make_driver(problem: Any, config: Any) -> RecedingDriver:
    return RecedingDriver(make_mission(config.problem, config.algorithm))


def with_settings(mission: Mission, **changes: Any) -> Mission:
    """A copy of ``mission`` with ``settings`` fields changed (fresh caches)."""
    return replace(mission, settings=replace(mission.settings, **changes), _cache={})
