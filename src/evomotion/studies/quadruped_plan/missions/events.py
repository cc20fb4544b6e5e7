"""World events of a receding-horizon walk (:mod:`.mission`): hidden obstacles coming into
view, the post that appears on the route, the goal that moves. Every draw comes from the
run's generator."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from evomotion.studies.quadruped_plan.missions.mission import Mission, MissionState

POST_SIDE = 1.2  # [units] side of an obstacle that appears
POST_AHEAD = 9.0  # [units] along the route: just beyond the view of hidden obstacles


def progress(mission: Mission, state: MissionState) -> float:
    """Share of the route walked, from the cost-to-go (0 at the start, 1 at the goal)."""
    route = mission.route(state)
    x, y = state.real[0], state.real[1]
    sx, sy, _ = mission.world.start
    now, first = route.cost[route.cell(x, y)], route.cost[route.cell(sx, sy)]
    if not (math.isfinite(now) and math.isfinite(first)) or first <= 0:
        return 0.0
    return 1.0 - now / first

def world_events(mission: Mission, state: MissionState, rng: np.random.Generator
                  ) -> tuple[MissionState, bool]:
    """Hidden obstacles in view, the appearing post, the goal moving."""
    x, y = state.real[0], state.real[1]
    changed = False
    hidden = mission.hidden()
    new = [i for i, p in enumerate(hidden) if i not in state.revealed and
           np.min(np.hypot(p.points[:, 0] - x, p.points[:, 1] - y)) <= mission.world.view]
    if new:
        state = replace(state, revealed=tuple(sorted((*state.revealed, *new))))
        changed = True
    d = mission.disturb
    index = len(state.path) - 1
    if not state.spawned and d.appear_probability > 0 and progress(mission, state) >= 1 / 3:
        post = None
        if rng.random() < d.appear_probability:
            post = _post(mission, state, rng.uniform(-1.0, 1.0))
        # () marks "decided": at most one post per mission
        state = replace(state, spawned=((post, index),) if post is not None else
                        ((None, index),))
        changed = changed or post is not None
    if state.goal_moved_at < 0 and d.goal_move > 0 and progress(mission, state) >= 0.5:
        goal = _moved_goal(mission, state, rng.uniform(-math.pi, math.pi))
        state = replace(state, goal=goal, goal_moved_at=index)
        changed = True
    return state, changed

def _post(mission: Mission, state: MissionState, lateral: float) -> list | None:
    """A square post on the route ``POST_AHEAD`` ahead, shifted ``lateral`` sideways."""
    pts = mission.route(state).path(state.real[0], state.real[1])
    if not pts:
        return None
    run, centre = 0.0, None
    for (ax, ay), (bx, by) in zip(pts, pts[1:]):
        seg = math.hypot(bx - ax, by - ay)
        if seg > 0 and run + seg >= POST_AHEAD:
            u = (POST_AHEAD - run) / seg
            nx, ny = -(by - ay) / seg, (bx - ax) / seg
            centre = (ax + u * (bx - ax) + lateral * nx, ay + u * (by - ay) + lateral * ny)
            break
        run += seg
    if centre is None:
        return None
    h = POST_SIDE / 2
    verts = [[centre[0] - h, centre[1] - h], [centre[0] + h, centre[1] - h],
             [centre[0] + h, centre[1] + h], [centre[0] - h, centre[1] + h]]
    x0, y0, x1, y1 = mission.world.bounds
    far = np.min(np.hypot(np.array(verts)[:, 0] - state.real[0],
                          np.array(verts)[:, 1] - state.real[1]))
    reach = mission.terrain(state).r_robot + 1.0
    goal_far = math.hypot(centre[0] - state.goal[0], centre[1] - state.goal[1]) > \
        h * math.sqrt(2) + reach
    if far < reach or not goal_far or not (x0 < centre[0] - h and centre[0] + h < x1 and
                                             y0 < centre[1] - h and centre[1] + h < y1):
        return None
    return verts

def _moved_goal(mission: Mission, state: MissionState, angle: float) -> tuple[float, float]:
    """The goal moved by ``goal_move`` at ``angle`` (or the next free direction)."""
    terrain = mission.terrain(state, truth=True)
    gx, gy = state.goal
    clear = terrain.r_hip + 1.0
    for k in range(12):
        a = angle + k * math.pi / 6
        nx, ny = gx + mission.disturb.goal_move * math.cos(a), gy + mission.disturb.goal_move * \
            math.sin(a)
        if terrain.body_distance(nx, ny) >= clear:
            return nx, ny
    return state.goal
