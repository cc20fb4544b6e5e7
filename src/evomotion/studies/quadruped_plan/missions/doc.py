"""The executed walk of a mission as a plan.json document (``mission.json``).

Same format as a plan (:mod:`.plan`), with ``"executed": true`` and, per state, ``event``
(``""`` for a rule, ``"landing"`` for a landing error, ``"slip N"`` for a slipped foot) and
``target`` (the sub-goal the rule steered at); ``world`` holds the world's polygons with the
posts that appeared (``from``: the state index from which they exist); ``goal`` is the goal
at the end, ``goal_history`` every goal with the state index from which it held. The
independent checker (:mod:`.checker`) verifies every state, rule, disturbance and obstacle.
"""

from __future__ import annotations

from typing import Any

from evomotion.studies.quadruped_plan.missions.mission import Mission, MissionState, summary
from evomotion.studies.quadruped_plan.plans.plan import plan_document, world_section


def mission_document(mission: Mission, state: MissionState) -> dict[str, Any]:
    states = [tuple(p["values"]) for p in state.path]
    rules = [p["rule"] for p in state.path]
    extras = [{"event": p["event"], "target": p["target"]} for p in state.path]
    posts = [("obstacle", v, i) for v, i in state.spawned if v is not None]
    world = world_section(mission.world, mission.body_clearance, mission.foot_clearance, posts)
    history = [{"goal": list(mission.world.goal), "from": 0}]
    if state.goal_moved_at >= 0:
        history.append({"goal": list(state.goal), "from": state.goal_moved_at})
    d = mission.disturb
    search = {"method": "receding-horizon", "planner": mission.planner,
              **{k: getattr(mission.settings, k) for k in (
                  "horizon", "replan_expansions", "replan_ms", "lookahead")},
              "disturbances": {k: getattr(d, k) for k in (
                  "foot_noise", "slip_probability", "slip_max", "appear_probability",
                  "goal_move")},
              **summary(state)}
    doc = plan_document(mission.model, states, rules, state.goal,
                        mission.world.goal_tolerance, mission.sense, mission.rule_set, None,
                        search, world, extras)
    doc["executed"] = True
    doc["goal_history"] = history
    # a disturbance moves one foot by at most this much [units] (landing: 5 sigma, clipped)
    doc["disturbance_max"] = max(d.slip_max, 5.0 * d.foot_noise)
    return doc
