"""Receding-horizon walking in a nondeterministic world (paper 003: "short-time plans" for a
robot in "an unknown, changing environment").

One replan: the route (:mod:`.route`) gives a sub-goal ``lookahead`` units ahead; ARA*
(:mod:`.anytime`) plans to it from the state the robot is really in, within
``replan_expansions`` and ``replan_ms``; the robot then executes the first ``horizon``
transitions by applying each planned *rule* to its real state in the real world. The world
deviates while it walks (all draws from the run's generator, so a seed fixes everything):

* **landing error**: a moved foot lands ``N(0, foot_noise)`` off its target (per axis) —
  where that spot is outside the foot's workspace or not allowed, it lands on the target
  (the foot-placement controller refuses it);
* **slip**: after a transition, with probability ``slip_probability``, one foot slides by
  ``U(0.3, 1) slip_max`` in a random direction (same validity rule; otherwise no slip);
* **an obstacle appears in view**: hidden obstacles of the world become known within
  ``view`` of the body centre, and with probability ``appear_probability`` a 1.2 x 1.2
  post appears on the route 9 units ahead once a third of the route is walked (off by default:
  the bundled worlds hide their own obstacles);
* **the goal moves**: once, half-way, by ``goal_move`` units in a random direction (to a
  free point).

A planned rule that is no longer applicable from the real state (a foot that may not be
lifted, a move into an obstacle) ends the execution early; anything that changes the world
model (a revealed obstacle, the goal moving) does too. A walk that keeps moving without
getting closer to the goal (:meth:`Mission.progress`: ``progress_transitions`` transitions
without getting ``PROGRESS_STEP`` closer along the route) replans with ``escalation`` times
the expansions, and fails with the reason when that does not help either. The mission state
is plain data (:class:`MissionState`), replaced step by step; the run loop checkpoints it as
JSON.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from evomotion.core.search import OPEN_EMPTY
from evomotion.errors import FileFormatError
from evomotion.studies.quadruped_plan.missions.events import world_events
from evomotion.studies.quadruped_plan.missions.recovery import STEP_BACK, step_back
from evomotion.studies.quadruped_plan.plans.anytime import WEIGHTS, ara_star
from evomotion.studies.quadruped_plan.rules.evaluation import PAPER_CONSTANTS, paper_evaluation
from evomotion.studies.quadruped_plan.rules.heuristic import plan_length_heuristic
from evomotion.studies.quadruped_plan.rules.model import QuadrupedModel
from evomotion.studies.quadruped_plan.rules.rules import WalkProblem, is_leg_rule
from evomotion.studies.quadruped_plan.worlds.route import Route
from evomotion.studies.quadruped_plan.worlds.terrain import Terrain, check_world_task
from evomotion.studies.quadruped_plan.worlds.world import Polygon, World

STUCK_REPLANS = 8  # replans in a row without a planned transition end the mission
PROGRESS_STEP = 0.5  # [units] progress: this much closer to the goal along the route
PLANNERS = ("anytime", "best-first")


@dataclass(frozen=True)
class Disturbances:
    foot_noise: float = 0.05  # [units] std of a landing error, per axis
    slip_probability: float = 0.03  # per transition
    slip_max: float = 0.3  # [units]
    appear_probability: float = 0.0  # a random post appears on the route (once)
    goal_move: float = 2.0  # [units] the goal moves once, half-way (0: never)


@dataclass(frozen=True)
class ReplanSettings:
    horizon: int = 8  # transitions executed per plan
    replan_expansions: int = 800
    replan_ms: float = 2000.0
    lookahead: float = 5.0  # [units] sub-goal distance along the route
    waypoint_tolerance: float = 1.0  # [units] goal tolerance of an intermediate sub-goal
    max_transitions: int = 2_000
    max_replans: int = 400
    progress_transitions: int = 100  # no progress over this many transitions: recover/fail
    escalation: int = 10  # expansion budget factor of the replans after a stall


@dataclass(frozen=True)
class MissionState:
    """Everything a mission has done; ``path`` rows are dicts (plan.json states + extras)."""

    real: tuple = ()  # the robot's state (11 floats)
    goal: tuple[float, float] = (0.0, 0.0)
    path: tuple = ()  # executed states: {"values", "rule", "event", "target"}
    revealed: tuple[int, ...] = ()  # indices of hidden polygons now known
    spawned: tuple = ()  # appeared posts: ((x, y) vertices, path index)
    replans: int = 0
    plan_ms: tuple[float, ...] = ()
    expansions: int = 0
    bounds: tuple[float, ...] = ()  # suboptimality bound of each complete plan (inf: partial)
    goal_moved_at: int = -1  # path index, -1 never
    idle: int = 0  # replans in a row that executed nothing
    route_length: float = 0.0
    done: str = ""  # "reached" or "failed: ..."
    time_bound: int = 0  # replans cut by replan_ms (then not reproducible)
    progress_best: float = math.inf  # least route distance to the goal since the world changed
    stalled: int = 0  # transitions since it last fell by PROGRESS_STEP
    escalated: bool = False  # replanning with ``escalation`` times the expansions


@dataclass
class Mission:
    """A world, the robot and the rules; builds terrains and routes for a state."""

    world: World
    model: QuadrupedModel
    rule_set: str = "A"
    sense: int = -1
    heuristic_gain: str = "analytic"
    settings: ReplanSettings = field(default_factory=ReplanSettings)
    disturb: Disturbances = field(default_factory=Disturbances)
    planner: str = "anytime"  # the paper's best-first (3) then ARA*, or the best-first alone
    body_clearance: float = 0.05  # [units]
    foot_clearance: float = 0.05  # [units]
    shifts: bool = False  # body shifts (rules 28-31, :mod:`.shifts`) in the search
    _cache: dict = field(default_factory=dict)

    # -- world views ----------------------------------------------------------------------
    def hidden(self) -> list[Polygon]:
        return self.world.of_kind("hidden")

    def terrain(self, state: MissionState, truth: bool = False) -> Terrain:
        key = ("truth" if truth else "known", state.revealed, len(state.spawned))
        if key not in self._cache:
            hidden = self.hidden()
            extra = [hidden[i] for i in range(len(hidden)) if truth or i in state.revealed]
            extra += [Polygon("obstacle", np.array(v)) for v, _ in state.spawned
                      if v is not None]
            self._trim()
            # the world's own obstacles once; what came into view is carved into a copy
            self._cache[key] = self._base_terrain().with_obstacles(extra)
        return self._cache[key]

    def _base_terrain(self) -> Terrain:
        if "base" not in self._cache:
            self._cache["base"] = Terrain(self.world, self.model, self.world.of_kind("obstacle"),
                                          self.body_clearance, self.foot_clearance)
        return self._cache["base"]

    def route(self, state: MissionState) -> Route:
        key = ("route", state.revealed, len(state.spawned), state.goal)
        if key not in self._cache:
            self._trim()
            self._cache[key] = Route(self.terrain(state), state.goal)
        return self._cache[key]

    def _trim(self) -> None:
        if len(self._cache) > 16:
            self._cache = {k: self._cache[k] for k in ("options", "base") if k in self._cache}

    def problem(self, real: tuple, target: tuple[float, float], tol: float,
                terrain: Terrain) -> WalkProblem:
        cache = self._cache.setdefault("options", [{}, {}, {}, {}])
        return WalkProblem(self.model, real, target, self.rule_set, tol, self.sense,
                           terrain=terrain, options_cache=cache, shifts=self.shifts)

    # -- start ------------------------------------------------------------------------------
    def start(self) -> MissionState:
        x, y, phi = self.world.start
        s0 = self.model.nominal_state(x, y, phi)
        base = MissionState(real=tuple(s0[:11]), goal=self.world.goal)
        check_world_task(self.world, self.model, self.body_clearance, self.foot_clearance)
        why = self.terrain(base, truth=True).stance_problem(s0)
        if why is not None:
            raise FileFormatError(self.world.source, self.world.start_line,
                                  f"start: the robot cannot stand there in its nominal stance "
                                  f"({why})")
        route = self.route(base)
        pts = route.path(x, y)
        length = sum(math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(pts, pts[1:])) \
            if pts else 0.0
        first = {"values": list(s0[:11]), "rule": 0, "event": "start",
                 "target": list(self.world.goal)}
        return replace(base, path=(first,), route_length=length,
                       progress_best=route.to_go(x, y))

    # -- one replan and its execution ---------------------------------------------------------
    def is_done(self, real: tuple, goal: tuple[float, float]) -> bool:
        return math.hypot(real[0] - goal[0], real[1] - goal[1]) <= self.world.goal_tolerance

    def target(self, state: MissionState) -> tuple[tuple[float, float], float]:
        """The sub-goal and its tolerance for the robot's real position."""
        x, y = state.real[0], state.real[1]
        sub = self.route(state).subgoal(x, y, self.settings.lookahead)
        if sub is None or math.hypot(sub[0] - state.goal[0], sub[1] - state.goal[1]) < 1e-9:
            return state.goal, self.world.goal_tolerance
        return sub, self.settings.waypoint_tolerance

    def step(self, state: MissionState, rng: np.random.Generator) -> MissionState:
        """Plan from the real state, execute up to ``horizon`` transitions."""
        cfg = self.settings
        t0 = time.perf_counter()
        before = state
        target, tol = self.target(state)
        known = self.terrain(state)
        problem = self.problem(state.real, target, tol, known)
        h = plan_length_heuristic(self.model, target, tol, self.sense, self.heuristic_gain,
                                  self.shifts)
        first = paper_evaluation(3, PAPER_CONSTANTS[(3, self.rule_set)], target, self.sense)
        budget = cfg.replan_expansions * (cfg.escalation if state.escalated else 1)
        plan = ara_star(problem, h, budget, cfg.replan_ms / 1000.0, first=first,
                        weights=() if self.planner == "best-first" else WEIGHTS)
        ms = 1000.0 * (time.perf_counter() - t0)
        state = replace(state, replans=state.replans + 1, plan_ms=(*state.plan_ms, ms),
                        expansions=state.expansions + plan.expansions,
                        bounds=(*state.bounds, plan.bound if plan.complete else math.inf),
                        time_bound=state.time_bound + plan.timed_out)
        executed = 0
        # a dead end (every reachable state searched, no plan): step back instead of
        # following a partial plan round it
        rules = [] if not plan.complete and plan.stop == OPEN_EMPTY else \
            plan.rules[1:1 + cfg.horizon]
        for rule in rules:
            if len(state.path) - 1 >= cfg.max_transitions:  # mission.json stays bounded
                break
            state, ok, changed = self.execute(state, rule, target, tol, rng)
            if not ok:
                break
            executed += 1
            if changed or state.done:
                break
        if not executed and not state.done:
            state = self.recover(state, target, tol, rng)
        state = replace(state, idle=0 if executed else state.idle + 1)
        if not state.done:
            state = self.progress(before, state)
        if not state.done:
            if len(state.path) - 1 >= cfg.max_transitions:
                state = replace(state, done=f"failed: {cfg.max_transitions} transitions")
            elif state.replans >= cfg.max_replans:
                state = replace(state, done=f"failed: {cfg.max_replans} replans")
            elif state.idle >= STUCK_REPLANS:
                state = replace(state, done=f"failed: stuck ({STUCK_REPLANS} replans "
                                            "without an applicable planned transition)")
        return state

    # -- the progress test ----------------------------------------------------------------
    def progress(self, before: MissionState, state: MissionState) -> MissionState:
        """Count the transitions since the robot last got ``PROGRESS_STEP`` closer to the
        goal along the route (:meth:`.route.Route.to_go`; the count restarts when the world
        model changes). After ``progress_transitions`` without progress the walker replans
        with ``escalation`` times the expansions until it progresses again; a second stall
        ends the walk with the reason (a livelock: a leg flipping between two rules, a step
        back and a step forward, round and round)."""
        cfg = self.settings
        if cfg.progress_transitions <= 0:
            return state
        now = self.route(state).to_go(state.real[0], state.real[1])
        if _world_key(before) != _world_key(state) or not math.isfinite(state.progress_best):
            return replace(state, progress_best=now, stalled=0, escalated=False)
        if now <= state.progress_best - PROGRESS_STEP:
            return replace(state, progress_best=now, stalled=0, escalated=False)
        moved = sum(1 for p in state.path[len(before.path):] if p["rule"] > 0)
        stalled = state.stalled + moved
        if stalled < cfg.progress_transitions:
            return replace(state, stalled=stalled)
        if not state.escalated and cfg.escalation > 1:
            return replace(state, stalled=0, escalated=True)
        return replace(state, stalled=stalled, done=self._no_progress(state))

    def _no_progress(self, state: MissionState) -> str:
        """The outcome of a walk that stopped progressing, with what it was doing."""
        cfg = self.settings
        recent = [p["rule"] for p in state.path[-2 * cfg.progress_transitions:]
                  if p["rule"] > 0][-cfg.progress_transitions:]
        counts: dict[int, int] = {}
        for r in recent:
            counts[r] = counts.get(r, 0) + 1
        top = sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))[:3]
        also = f", also with {cfg.replan_expansions * cfg.escalation:,} expansions per " \
            "replan" if cfg.escalation > 1 else ""
        far = math.hypot(state.real[0] - state.goal[0], state.real[1] - state.goal[1])
        return (f"failed: no progress ({cfg.progress_transitions} transitions without getting "
                f"{PROGRESS_STEP:g} units closer to the goal along the route{also}; "
                f"{far:.1f} units from the goal; most used rules: "
                + ", ".join(f"{r} x{n}" for r, n in top) + ")")

    def step_back_state(self, state: MissionState, target: tuple[float, float], tol: float
                        ) -> tuple | None:
        """The state after a step back in the real world, or None when the body cannot."""
        problem = self.problem(state.real, target, tol, self.terrain(state, truth=True))
        return step_back(problem, problem.start())

    def recover(self, state: MissionState, target: tuple[float, float], tol: float,
                rng: np.random.Generator) -> MissionState:
        """One recovery move (:mod:`.recovery`) when no planned transition applied."""
        child = self.step_back_state(state, target, tol)
        if child is None:
            return state
        path = (*state.path, {"values": list(child[:11]), "rule": STEP_BACK, "event": "",
                              "target": list(target)})
        state = replace(state, real=tuple(child[:11]), path=path)
        state, _ = world_events(self, state, rng)
        if self.is_done(state.real, state.goal):
            state = replace(state, done="reached")
        return state

    def apply(self, real: tuple, rule: int, target: tuple[float, float], tol: float,
              terrain: Terrain) -> tuple | None:
        """The rule applied to the real state in ``terrain`` (None: not applicable)."""
        problem = self.problem(real, target, tol, terrain)
        return next((c for r, c, _ in problem.successors(problem.start()) if r == rule), None)

    def execute(self, state: MissionState, rule: int, target: tuple[float, float],
                tol: float, rng: np.random.Generator) -> tuple[MissionState, bool, bool]:
        """One planned transition in the real world, then its disturbances. Returns the new
        state, whether the rule applied, and whether the world model changed."""
        truth = self.terrain(state, truth=True)
        child = self.apply(state.real, rule, target, tol, truth)
        if child is None:
            return state, False, False
        path = [*state.path, {"values": list(child[:11]), "rule": int(rule), "event": "",
                              "target": list(target)}]
        real = tuple(child[:11])
        d = self.disturb
        if is_leg_rule(rule) and d.foot_noise > 0:  # landing error of the moved foot
            leg = (rule - 4) % 4
            err = rng.normal(0.0, d.foot_noise, 2)
            norm = float(np.hypot(*err))
            if norm > 5.0 * d.foot_noise:  # clipped at 5 sigma (the checker's bound)
                err *= 5.0 * d.foot_noise / norm
            moved = self._moved_foot(real, leg, err, truth)
            if moved is not None:
                real = moved
                path.append({"values": list(real), "rule": 0, "event": "landing",
                             "target": list(target)})
        if d.slip_probability > 0 and rng.random() < d.slip_probability:
            leg = int(rng.integers(4))
            ang = rng.uniform(-math.pi, math.pi)
            length = rng.uniform(0.3, 1.0) * d.slip_max
            moved = self._moved_foot(real, leg, np.array([math.cos(ang), math.sin(ang)]) *
                                     length, truth)
            if moved is not None:
                real = moved
                path.append({"values": list(real), "rule": 0, "event": f"slip {leg}",
                             "target": list(target)})
        state = replace(state, real=real, path=tuple(path))
        state, changed = world_events(self, state, rng)
        if self.is_done(real, state.goal):
            state = replace(state, done="reached")
        return state, True, changed

    def _moved_foot(self, real: tuple, leg: int, dw: np.ndarray, truth: Terrain
                    ) -> tuple | None:
        """``real`` with foot ``leg`` moved by world vector ``dw``, if that is allowed."""
        c, s = math.cos(real[2]), math.sin(real[2])
        j = 3 + 2 * leg
        fx = real[j] + c * dw[0] + s * dw[1]
        fy = real[j + 1] - s * dw[0] + c * dw[1]
        m = self.model
        hx, hy = m.hips[leg]
        length = math.hypot(fx - hx, fy - hy)
        off = (math.atan2(fy - hy, fx - hx) - m.nominal_angle(leg) + math.pi) % (2 * math.pi) \
            - math.pi
        if not (m.l_min <= length <= m.l_max and abs(off) <= m.sector_half_width):
            return None
        wx, wy = real[0] + c * fx - s * fy, real[1] + s * fx + c * fy
        if not truth.foot_ok(wx, wy):
            return None
        out = list(real)
        out[j], out[j + 1] = fx, fy
        return tuple(out)


def _world_key(state: MissionState) -> tuple:
    """What the route depends on: obstacles in view, posts that appeared, the goal."""
    return state.revealed, len(state.spawned), state.goal


def run_mission(mission: Mission, rng: np.random.Generator) -> MissionState:
    """A whole mission (the run loop steps :meth:`Mission.step` instead)."""
    state = mission.start()
    while not state.done:
        state = mission.step(state, rng)
    return state


def summary(state: MissionState) -> dict[str, Any]:
    ms = np.array(state.plan_ms) if state.plan_ms else np.zeros(1)
    bounded = [b for b in state.bounds if math.isfinite(b)]  # ARA* iterations that finished
    rules = [p for p in state.path[1:] if p["rule"] > 0]
    return {"reached": state.done == "reached", "outcome": state.done,
            "transitions": len(rules), "replans": state.replans,
            "plan_ms_median": float(np.median(ms)), "plan_ms_max": float(np.max(ms)),
            "expansions": state.expansions,
            "expansions_per_s": state.expansions / max(1e-9, float(np.sum(ms)) / 1000.0),
            "events": sum(1 for p in state.path if p["event"] not in ("", "start")),
            "recoveries": sum(1 for p in state.path if p["rule"] == STEP_BACK),
            "bounded_replans": len(bounded),
            "bound_median": float(np.median(bounded)) if bounded else None,
            "time_bound_replans": state.time_bound}
