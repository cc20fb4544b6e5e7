"""Paper 001's schedule (section 2) as a driver: N arm generations, then M finger generations,
then whole-limb generations until a solution is found or the budget ends, with restarts.

In the arm phase the objective is the wrist's distance to the nearest wrist-candidate cell
and only arm bones count as intersections; in the finger and whole-limb phases it is the sum
of matched tip-target distances and every bone counts (section 3.3). A solution: every tip
within ``tolerance * diagonal`` of a distinct target, no intersection, all limits respected.
When the whole-limb phase gains less than 1% in ``restart_after`` generations, the schedule
restarts from a fresh population (the best limb found so far is kept).

One driver step is one generation (the first step evaluates the initial population); the
state is explicit, so a run stops, checkpoints and resumes like any other.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from evomotion.core.checks import MAX_POP_SIZE, check_fields, check_number
from evomotion.core.problem import Sense
from evomotion.core.state import replaced
from evomotion.errors import InputError
from evomotion.run.driver import Driver, Evaluate, StepReport
from evomotion.studies.arm_ik.evolution import crossover, mutate, parents, rank_order, survivors
from evomotion.studies.arm_ik.problem import ArmIKProblem, Assessment

EXTRA_COLUMNS = (
    "phase", "best_objective", "best_intersections", "best_feasible_objective",
    "mean_objective", "var_objective", "mean_intersections", "var_intersections",
    "originality", "feasible_fraction", "best_limb_distance", "best_limb_intersections",
    "best_limb_max_tip_error", "solved", "restarts",
)


@dataclass(frozen=True)
class ScheduleConfig:
    """``[algorithm]`` of arm-ik (``name = "schedule"``): the paper's GA and its phases."""

    name: str = "schedule"
    pop_size: int = 60
    arm_generations: int = 15  # the paper's schedule: N arm generations,
    finger_generations: int = 15  # then M finger generations,
    whole_generations: int = 3000  # then whole-limb generations (until solved)
    restart_after: int = 60  # whole-limb generations without a 1% gain -> restart (0 = never)
    tournament_k: int = 2  # parent tournament size
    blend_prob: float = 0.5  # per active gene: beta-blend, else inherit (uniform swap)
    circular_blend: bool = True  # blend full-circle angles along the shorter arc
    mutation_rate: float = 1.0  # probability that a child gets one angle perturbed
    mutation_min_deg: float = 1e-3  # perturbation magnitude is log-uniform in [min, max]
    mutation_max_deg: float = 60.0
    infeasible_fraction: float = 0.1  # IDEA: share of survivors kept infeasible
    survival: str = "pairwise"  # pairwise | tournament (paper's literal: with replacement)
    stop_when_solved: bool = True

    def validate(self) -> None:
        check_fields(self, "algorithm")
        check_number("algorithm.pop_size", self.pop_size, hi=MAX_POP_SIZE, integer=True)
        for key in ("blend_prob", "mutation_rate"):
            check_number(f"algorithm.{key}", getattr(self, key), lo=0.0, hi=1.0)
        check_number("algorithm.mutation_max_deg", self.mutation_max_deg, hi=360.0)
        if self.survival not in ("pairwise", "tournament"):
            raise InputError(f"algorithm.survival: expected pairwise or tournament, "
                             f"got {self.survival!r}")
        if self.pop_size < 4 or self.pop_size % 2:
            raise InputError(f"algorithm.pop_size: expected an even number >= 4, "
                             f"got {self.pop_size}")
        if not 0 <= self.infeasible_fraction < 1:
            raise InputError("algorithm.infeasible_fraction: expected a value in [0, 1)")
        if not 0 < self.mutation_min_deg <= self.mutation_max_deg:
            raise InputError("algorithm.mutation_min_deg/max_deg: expected 0 < min <= max")
        for k in ("arm_generations", "finger_generations", "whole_generations",
                  "restart_after", "tournament_k"):
            if getattr(self, k) < 0:
                raise InputError(f"algorithm.{k}: expected >= 0, got {getattr(self, k)}")
        check_number("algorithm.tournament_k", self.tournament_k, lo=1, hi=self.pop_size,
                     integer=True)


def phase_objective(a: Assessment, mode: str) -> tuple[np.ndarray, np.ndarray]:
    """(objective, intersections) that rank individuals in phase ``mode``."""
    if mode == "arm":
        return a.wrist_distance, a.arm_intersections
    return a.distance, a.intersections


def limb_key(a: Assessment) -> np.ndarray:
    return rank_order(a.intersections, a.distance)


@dataclass
class ScheduleState:
    pop: np.ndarray
    assessment: Assessment
    best_x: np.ndarray
    best_a: Assessment
    history: np.ndarray  # (generations + 1, dim): best whole limb after each generation
    generation: int = -1  # -1: the initial population is not evaluated yet
    phase: str = "arm"
    in_phase: int = 0  # generations done in the arm or finger phase
    whole_left: int = 0
    mark: float = float("inf")
    mark_generation: int = 0
    restarts: int = 0
    mode: str = "init"  # phase of the last generation
    elapsed_s: float = 0.0  # wall time in this driver's steps (and building the problem)
    cpu_s: float = 0.0  # process CPU time before this process's first step (build, resumes)
    solved_s: float = float("nan")  # elapsed_s when the first solution was found
    solved_cpu_s: float = float("nan")


class ScheduleDriver(Driver):
    """Steps the schedule on an :class:`ArmIKProblem`."""

    sense: Sense = "min"
    extra_columns = EXTRA_COLUMNS

    def __init__(self, problem: ArmIKProblem, cfg: ScheduleConfig) -> None:
        cfg.validate()
        self.problem, self.cfg = problem, cfg
        self._cpu0: float | None = None  # process CPU time at this process's first step

    def init(self, rng: np.random.Generator) -> ScheduleState:
        d = self.problem.genome.dim
        empty = Assessment(np.zeros((0,)), np.zeros((0,)), np.zeros((0,)), np.zeros((0,)),
                           np.zeros((0, 1)), np.zeros((0, 1), int), np.zeros((0, 1, 2)),
                           np.zeros(0, bool))
        return ScheduleState(np.zeros((0, d)), empty, np.full(d, np.nan), empty,
                             np.zeros((0, d)), whole_left=self.cfg.whole_generations,
                             elapsed_s=self.problem.build_seconds,
                             cpu_s=self.problem.build_cpu_s)

    def best(self, state: ScheduleState) -> tuple[np.ndarray, float]:
        if state.generation < 0:
            return state.best_x, float("inf")
        return state.best_x, float(self.problem.fitness(state.best_a)[0])

    def check_state(self, state: ScheduleState) -> None:
        d, n = self.problem.genome.dim, self.cfg.pop_size
        if state.generation >= 0 and (state.pop.shape != (n, d)
                                      or len(state.assessment.distance) != n
                                      or state.history.shape != (state.generation + 1, d)):
            raise ValueError(f"population {state.pop.shape} / history {state.history.shape} "
                             f"do not fit pop_size {n}, {d} genes, generation "
                             f"{state.generation}")
        if state.phase not in ("arm", "fingers", "whole"):
            raise ValueError(f"unknown phase {state.phase!r}")

    def stop(self, state: ScheduleState) -> str | None:
        if state.generation < 0:
            return None
        if self.cfg.stop_when_solved and bool(state.best_a.solved[0]):
            return "solved"
        if self._next_phase(state.phase, state.in_phase) == "whole" and state.whole_left <= 0:
            return "whole_generations"
        return None

    def step(self, state: ScheduleState, rng: np.random.Generator,
             evaluate: Evaluate) -> tuple[ScheduleState, StepReport]:
        t0 = time.perf_counter()
        if self._cpu0 is None:  # process CPU time is read twice per run (it is slow in VMs)
            self._cpu0 = time.process_time()
        s = replaced(state)  # a shallow copy; the generation replaces the arrays it changes
        n_eval, failed, errors = 0, 0, []

        def assess(x: np.ndarray) -> Assessment:
            nonlocal n_eval, failed
            ev = evaluate(x)
            n_eval += len(x)
            failed += int(ev.failed.sum()) if ev.failed is not None else 0
            errors.extend(ev.errors)
            return self.problem.assessment_of(ev)

        mode = "init"
        if s.generation < 0:
            s.pop = self.problem.genome.sample(rng, self.cfg.pop_size)
            s.assessment = assess(s.pop)
            i = int(np.argmin(limb_key(s.assessment)))
            s.best_x, s.best_a = s.pop[i].copy(), s.assessment.take(np.array([i]))
            s.history = s.best_x[None].copy()
            s.phase = self._next_phase("arm", 0)
        else:
            mode = self._advance(s, rng, assess)
            self._generation(s, mode, rng, assess)
        s.generation += 1
        s.elapsed_s += time.perf_counter() - t0
        if bool(s.best_a.solved[0]) and np.isnan(s.solved_s):
            s.solved_s = s.elapsed_s
            s.solved_cpu_s = s.cpu_s + time.process_time() - self._cpu0
        report = self._report(s, mode, n_eval, failed, errors, changed=mode != state.mode)
        s.mode = mode
        return s, report

    def _next_phase(self, phase: str, done: int) -> str:
        if phase == "arm" and done >= self.cfg.arm_generations:
            phase, done = "fingers", 0
        if phase == "fingers" and done >= self.cfg.finger_generations:
            phase = "whole"
        return phase

    def _advance(self, s: ScheduleState, rng: np.random.Generator, assess) -> str:
        """The phase of this step's generation (after any phase change or restart)."""
        for _ in range(3):
            nxt = self._next_phase(s.phase, s.in_phase)
            if nxt != s.phase:
                s.phase, s.in_phase = nxt, 0
                if nxt == "whole":
                    s.mark, s.mark_generation = float("inf"), s.generation
            if s.phase != "whole":
                s.in_phase += 1
                return s.phase
            d = float(s.assessment.distance[np.argmin(limb_key(s.assessment))])
            if d < 0.99 * s.mark:
                s.mark, s.mark_generation = d, s.generation
            elif self.cfg.restart_after and \
                    s.generation - s.mark_generation >= self.cfg.restart_after:
                s.restarts += 1
                s.pop = self.problem.genome.sample(rng, self.cfg.pop_size)
                s.assessment = assess(s.pop)
                s.phase, s.in_phase = "arm", 0
                continue
            s.whole_left -= 1
            return "whole"
        raise RuntimeError("arm-ik schedule: no phase left to run")

    def _generation(self, s: ScheduleState, mode: str, rng: np.random.Generator,
                    assess) -> None:
        cfg, lay, N = self.cfg, self.problem.layout, self.cfg.pop_size
        obj, hits = phase_objective(s.assessment, mode)
        ia, ib = parents(rank_order(hits, obj), N // 2, rng, cfg.tournament_k)
        kids = crossover(s.pop[ia], s.pop[ib], lay, mode, rng, cfg.blend_prob,
                         cfg.circular_blend)
        kids = mutate(kids, lay, mode, rng, cfg.mutation_rate, cfg.mutation_min_deg,
                      cfg.mutation_max_deg)
        K = assess(kids)
        pool, PA = np.concatenate([s.pop, kids]), Assessment.concat(s.assessment, K)
        obj, hits = phase_objective(PA, mode)
        keep = survivors(hits, obj, N, rng, cfg.infeasible_fraction, cfg.survival == "pairwise")
        # best whole limb so far (a child may hold it even when its phase ranks it low)
        j = int(np.argmin(limb_key(K)))
        if limb_key(Assessment.concat(s.best_a, K.take(np.array([j]))))[1] == 0:
            s.best_x, s.best_a = kids[j].copy(), K.take(np.array([j]))
        s.pop, s.assessment = pool[keep], PA.take(keep)
        s.history = np.concatenate([s.history, s.best_x[None]])

    def _report(self, s: ScheduleState, mode: str, n: int, failed: int,
                errors: list[str], changed: bool) -> StepReport:
        A, b_a = s.assessment, s.best_a
        obj, hits = phase_objective(A, "arm" if mode == "arm" else "whole")
        r = rank_order(hits, obj)
        b = int(np.argmin(r))
        feas = hits == 0
        extras = {
            "phase": mode, "best_objective": float(obj[b]), "best_intersections": int(hits[b]),
            "best_feasible_objective": float(obj[feas].min()) if feas.any() else float("nan"),
            **_mean_var("objective", obj), **_mean_var("intersections", hits),
            "originality": distinct_rows(s.pop) / s.pop.shape[0],
            "feasible_fraction": float(feas.mean()),
            "best_limb_distance": float(b_a.distance[0]),
            "best_limb_intersections": int(b_a.intersections[0]),
            "best_limb_max_tip_error": float(b_a.tip_error[0].max()),
            "solved": int(b_a.solved[0]), "restarts": s.restarts,
        }
        metrics = {"distance": float(b_a.distance[0]),
                   "intersections": float(b_a.intersections[0]),
                   "max_tip_error": float(b_a.tip_error[0].max()),
                   "solved": float(b_a.solved[0])}
        lines = [f"{mode} phase" + (f" (restart {s.restarts})" if s.restarts and mode == "arm"
                                    else "")] if changed and mode != "init" else []
        return StepReport(n, self.problem.fitness(A), s.pop, failed, errors, metrics, extras,
                          lines)


def _mean_var(name: str, x: np.ndarray) -> dict[str, float]:
    """``mean_<name>`` and ``var_<name>``: the values of ``x.mean()`` and ``x.var()``
    without their per-call overhead (the report runs every generation)."""
    x = np.asarray(x, dtype=float)
    m = x.sum() / x.size
    d = x - m
    return {f"mean_{name}": float(m), f"var_{name}": float((d * d).sum() / x.size)}


def distinct_rows(x: np.ndarray) -> int:
    """Number of distinct rows of ``x[n, d]`` (``np.unique(x, axis=0)``'s row count, by one
    lexicographic sort; ``-0.0`` and ``0.0`` count as equal)."""
    if len(x) < 2:
        return len(x)
    s = x[np.lexsort(x.T[::-1])]
    return 1 + int((s[1:] != s[:-1]).any(1).sum())


def make_driver(problem: ArmIKProblem, config) -> ScheduleDriver:
    return ScheduleDriver(problem, config.algorithm)


#: the study's own method (``[algorithm]`` name ``schedule``), for its descriptor and its
#: in-memory runs
OWN_ALGORITHMS = {"schedule": (ScheduleConfig, make_driver)}
