"""Arm-IK problem of paper 001: configuration, batch assessment and the Problem protocol."""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from evomotion.core.checks import check_fields, check_number, check_text
from evomotion.core.problem import Evaluation, GenomeSpec, Sense
from evomotion.errors import InputError
from evomotion.studies.arm_ik.geometry import segment_hits
from evomotion.studies.arm_ik.heuristics import WristMap, build_wrist_map
from evomotion.studies.arm_ik.kinematics import Layout, forward
from evomotion.studies.arm_ik.objective import (
    DISTANCES,
    MATCHINGS,
    greedy_match,
    keys_match,
    matched,
    optimal_match,
    straight_distances,
)
from evomotion.studies.arm_ik.scenario import MAX_ABS, Scenario, load_scenario
from evomotion.studies.arm_ik.visibility import VisibilityGraph

#: ``problem.gif_frames`` at most; heuristic-map cells along the board's diagonal at most
MAX_GIF_FRAMES = 1000
MAX_CELLS_PER_SIDE = 3000


@dataclass(frozen=True)
class ArmIKConfig:
    """``[problem]`` section of the arm-ik study (angles in degrees, lengths in board units).

    The GA and its schedule are the ``[algorithm]`` section
    (:class:`evomotion.studies.arm_ik.schedule.ScheduleConfig`)."""

    scenario: str = "paper_example"  # bundled name or path to a scenario file
    matching: str = "optimal"  # greedy | optimal | chromosome
    distance: str = "straight"  # straight | obstacle (way around the obstacles)
    board_walls: bool = True  # a joint outside the board counts as one intersection
    cell_size: float = 0.0  # heuristic cell side (board units, at most 1e6); 0 = diagonal / 150
    tolerance: float = 1e-3  # solved: every tip within tolerance * diagonal of its target
    pictures: bool = True  # board.png and best.gif in the run folder
    gif_frames: int = 30

    def validate(self) -> None:
        check_fields(self, "problem")
        check_text("problem.scenario", self.scenario, empty=False)
        check_number("problem.cell_size", self.cell_size, lo=0.0, hi=MAX_ABS)
        check_number("problem.tolerance", self.tolerance, lo=0.0, hi=1.0, lo_open=True)
        check_number("problem.gif_frames", self.gif_frames, lo=1, hi=MAX_GIF_FRAMES, integer=True)
        if self.matching not in MATCHINGS:
            raise InputError(f"problem.matching: expected one of {', '.join(MATCHINGS)}, "
                             f"got {self.matching!r}")
        if self.distance not in DISTANCES:
            raise InputError(f"problem.distance: expected one of {', '.join(DISTANCES)}, "
                             f"got {self.distance!r}")


@dataclass
class Assessment:
    """Everything measured about a batch of limbs (arrays over the population)."""

    wrist_distance: np.ndarray  # (n,) to the nearest wrist-candidate cell (arm phase objective)
    arm_intersections: np.ndarray  # (n,) arm bones x obstacle edges
    intersections: np.ndarray  # (n,) all bones x obstacle edges
    distance: np.ndarray  # (n,) sum of matched tip distances (finger / whole phase objective)
    tip_error: np.ndarray  # (n, F) straight-line matched tip-target distances
    assignment: np.ndarray  # (n, F) target index of each finger
    tips: np.ndarray  # (n, F, 2)
    solved: np.ndarray  # (n,) bool

    def take(self, idx: np.ndarray) -> Assessment:
        return Assessment(**{k: v[idx] for k, v in vars(self).items()})

    @staticmethod
    def concat(a: Assessment, b: Assessment) -> Assessment:
        return Assessment(**{k: np.concatenate([v, getattr(b, k)]) for k, v in vars(a).items()})


_ASSESSMENT_FIELDS = tuple(f.name for f in dataclasses.fields(Assessment))


class ArmIKProblem:
    """Batch evaluation of limbs; ``evaluate`` gives the penalised whole-limb fitness."""

    sense: Sense = "min"
    metric_names: tuple[str, ...] = ("distance", "intersections", "max_tip_error", "solved")

    def __init__(self, cfg: ArmIKConfig, scenario: Scenario | None = None) -> None:
        t0, c0 = time.perf_counter(), time.process_time()
        cfg.validate()
        self.cfg = cfg
        self.scn = scenario if scenario is not None else load_scenario(cfg.scenario)
        if cfg.cell_size > 0 and self.scn.diagonal / cfg.cell_size > MAX_CELLS_PER_SIDE:
            raise InputError(f"problem.cell_size: expected >= {self.scn.diagonal:g} / "
                             f"{MAX_CELLS_PER_SIDE} (the board's diagonal / the most cells "
                             f"per side) for scenario {self.scn.name!r}, got {cfg.cell_size}")
        self.layout = Layout.of(self.scn, with_keys=cfg.matching == "chromosome")
        self.genome = GenomeSpec(self.layout.lower, self.layout.upper)
        self.obstacles = self.scn.obstacle_segments()
        self.wrist_map: WristMap = build_wrist_map(self.scn, cfg.cell_size)
        self.visibility = VisibilityGraph.build(self.scn) if cfg.distance == "obstacle" else None
        self.tol = cfg.tolerance * self.scn.diagonal
        # the heuristics are part of the method: the schedule's time to solution counts them
        self.build_seconds = time.perf_counter() - t0
        self.build_cpu_s = time.process_time() - c0

    def assess(self, genomes: np.ndarray) -> Assessment:
        g = np.atleast_2d(np.asarray(genomes, dtype=float))
        pose = forward(self.scn, self.layout, g)
        segs = np.concatenate([pose.arm_segments(), pose.finger_segments()], axis=1)
        mask = np.concatenate([np.ones(self.layout.n_arm, bool), self.layout.finger_mask.ravel()])
        per = segment_hits(segs, self.obstacles) * mask
        hits, arm_hits = per.sum(axis=1), per[:, : self.layout.n_arm].sum(axis=1)
        if self.cfg.board_walls:  # the board is convex: a bone leaves it iff a joint does
            out_arm = self._outside(pose.arm_joints[:, 1:]).sum(axis=1)
            out_f = self._outside(pose.finger_joints[:, :, 1:]) & self.layout.finger_mask
            arm_hits = arm_hits + out_arm
            hits = hits + out_arm + out_f.sum(axis=(1, 2))
        tips = pose.tips
        straight = straight_distances(tips, self.scn.targets)
        D = straight
        if self.visibility is not None:
            D = self.visibility.distances(tips)
            D = np.where(np.isfinite(D), D, straight + self.scn.diagonal)  # tip inside a wall
        if self.cfg.matching == "greedy":
            assign = greedy_match(D)
        elif self.cfg.matching == "optimal":
            assign = optimal_match(D)
        else:
            assign = keys_match(g[:, self.layout.keys])
        tip_err = matched(straight, assign)
        in_limits = np.all((g >= self.layout.lower) & (g <= self.layout.upper), axis=1)
        solved = (hits == 0) & np.all(tip_err <= self.tol, axis=1) & in_limits
        return Assessment(self.wrist_map.wrist_distance(pose.wrist), arm_hits, hits,
                          matched(D, assign).sum(axis=1), tip_err, assign, tips, solved)

    def _outside(self, pts: np.ndarray) -> np.ndarray:
        x, y = pts[..., 0], pts[..., 1]
        return (x < 0) | (y < 0) | (x > self.scn.width) | (y > self.scn.height)

    def evaluate(self, genomes: np.ndarray) -> Evaluation:
        """Whole-limb fitness ``distance + diagonal * intersections``; the metrics carry the
        whole :class:`Assessment` (keys ``assessment.<field>``) for the schedule's phases."""
        a = self.assess(genomes)
        metrics = {"distance": a.distance, "intersections": a.intersections.astype(float),
                   "max_tip_error": a.tip_error.max(axis=1), "solved": a.solved.astype(float)}
        metrics.update({f"assessment.{k}": v for k, v in vars(a).items()})
        return Evaluation(self.fitness(a), metrics)

    def fitness(self, a: Assessment) -> np.ndarray:
        return a.distance + self.scn.diagonal * a.intersections

    def assessment_of(self, ev: Evaluation) -> Assessment:
        """The :class:`Assessment` carried by ``ev`` (from any evaluator); an individual
        whose evaluation failed counts as infinitely far with one intersection per bone."""
        fields = _ASSESSMENT_FIELDS
        if all(f"assessment.{k}" in ev.metrics for k in fields):
            a = Assessment(**{k: np.asarray(ev.metrics[f"assessment.{k}"]) for k in fields})
        else:
            n, F = len(ev), self.scn.n_targets
            a = Assessment(np.full(n, np.inf), np.ones(n, int), np.ones(n, int),
                           np.full(n, np.inf), np.full((n, F), np.inf), np.zeros((n, F), int),
                           np.full((n, F, 2), np.nan), np.zeros(n, bool))
        if ev.failed is not None and ev.failed.any():
            bad = ev.failed
            a.distance = np.where(bad, np.inf, a.distance)
            a.wrist_distance = np.where(bad, np.inf, a.wrist_distance)
            a.solved = a.solved & ~bad
        return a


def make_problem(cfg: ArmIKConfig) -> ArmIKProblem:
    return ArmIKProblem(cfg)
