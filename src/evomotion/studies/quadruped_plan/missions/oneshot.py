"""The one-shot baseline of the receding-horizon walker.

One plan to the goal, made before the robot moves, in the world as known at the start
(hidden obstacles unknown, no disturbances): the same route and sub-goals as the walker,
each sub-plan found with a large budget (``ONE_SHOT_EXPANSIONS``) and followed to its end.
The robot then executes that rule sequence open loop in the real world with the same kinds
of disturbances (:mod:`.mission`): each rule is applied to the real state; the first rule
that no longer applies (a foot that may not be lifted, a move into an obstacle) ends the
walk. Success = the goal (where it is at the end) reached.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import numpy as np

from evomotion.studies.quadruped_plan.missions.mission import (
    Disturbances,
    Mission,
    MissionState,
    run_mission,
)

ONE_SHOT_EXPANSIONS = 20_000


def plan_once(mission: Mission, expansions: int = ONE_SHOT_EXPANSIONS
              ) -> tuple[MissionState, float]:
    """The one-shot plan (a noise-free walk in the known world, ``expansions`` per sub-plan)
    and its planning time [ms]."""
    known = replace(mission.world, polygons=tuple(p for p in mission.world.polygons
                                                   if p.kind != "hidden"))
    quiet = replace(mission, world=known, disturb=Disturbances(0.0, 0.0, 0.0, 0.0, 0.0),
                    settings=replace(mission.settings, horizon=10**9,
                                     replan_expansions=expansions,
                                     replan_ms=1e9), _cache={})
    t0 = time.perf_counter()
    state = run_mission(quiet, np.random.default_rng(0))
    return state, 1000.0 * (time.perf_counter() - t0)


def execute_open_loop(mission: Mission, plan: MissionState, rng: np.random.Generator
                      ) -> MissionState:
    """The plan's rules applied in turn to the real state, with disturbances."""
    state = mission.start()
    tol = mission.world.goal_tolerance
    for entry in plan.path[1:]:
        if entry["event"] or entry["rule"] == 0:
            continue
        target = tuple(entry["target"])
        state, ok, _ = mission.execute(state, entry["rule"], target, tol, rng)
        if not ok:
            return replace(state, done=f"failed: rule {entry['rule']} not applicable")
        if state.done:
            break
    if not state.done:
        state = replace(state, done="reached" if mission.is_done(state.real, state.goal)
                        else "failed: the plan ends away from the goal")
    return state


def one_shot(mission: Mission, rng: np.random.Generator,
             plan: tuple[MissionState, float] | None = None) -> dict[str, Any]:
    """Figures of the one-shot baseline (``plan``: a precomputed :func:`plan_once`)."""
    planned, ms = plan or plan_once(mission)
    if planned.done != "reached":
        return {"reached": False, "outcome": f"no one-shot plan ({planned.done})",
                "transitions": 0, "plan_ms": ms, "planned_transitions": 0, "state": planned}
    walked = execute_open_loop(mission, planned, rng)
    return {"reached": walked.done == "reached", "outcome": walked.done,
            "transitions": sum(1 for p in walked.path if p["rule"] > 0), "plan_ms": ms,
            "planned_transitions": sum(1 for p in planned.path if p["rule"] > 0),
            "state": walked}
