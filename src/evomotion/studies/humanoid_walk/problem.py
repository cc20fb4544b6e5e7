"""The walk problem: evaluate a batch of gait parameters (:mod:`.gait`) on the NAO.

Each genome is decoded into its key poses (every 20 ms: start-up, ramps, steady cycles for
``walk_s`` seconds, stop) and those into one servo target per physics step by exactly the
linear interpolation :func:`evomotion.sim.nao.replay.motion_targets` applies to a ``.motion``,
from the same initial state and on the same model (``nao.load_model()``), so the exported
``best.motion`` replayed with ``evomotion replay --hold H`` is the evaluated rollout. Every
rollout lasts ``horizon_s`` (the longest schedule the period bounds allow, plus ``hold_s``);
shorter walks hold their ready pose to the end. Fallen robots stop being simulated at
``segment_s`` boundaries.

Fitness (maximised; units in brackets), like humanoid-step's it ranks every robot that stays
up above every robot that falls and never saturates:

- fell: ``time_up_s`` [s] ``+ 0.1 clip(forward_m, -0.5, 0.5)``, below ``horizon_s``;
- stayed up: ``horizon_s + 1 + soft_floor(quality_m)`` (:func:`soft_floor`),
  ``quality_m = forward_m - heading_weight |heading_change_rad| - lateral_weight
  |lateral_m| - excess_weight max(|heading_change_rad| - heading_tolerance_rad_per_m
  max(forward_m, 0), 0) - energy_weight cost_of_transport`` [m]: forward torso
  displacement over the walk, penalised by turning (1 m/rad), sideways drift (1 m/m),
  turning beyond 5 degrees per metre walked
  (20 m/rad more) and the cost of transport (mechanical work ``sum |tau qdot| dt`` of the 22
  servos over ``m g forward``; ``tau = clip(kp (target - q), force range)``, the position
  servo of the model; 0.05 m per unit).
- stayed up but too fast for the real robot (a joint moves faster between two key poses than
  ``speed_margin`` times its motor's no-load speed, :data:`~evomotion.sim.nao.joint_limits.
  SPEED_LIMITS`): ``horizon_s + 0.5 - 0.49 tanh(speed_ratio - 1)``, between the fallen and
  the playable walks, so the best walk can always be exported to a NAO.

Perturbed worlds (``worlds = K``: the nominal world and K - 1 drawn from the run seed, by
default as a Latin hypercube over the ranges of :class:`~evomotion.sim.nao.worlds.Perturbation`,
pushes during the walk of up to ``train_push_ns`` = 3.5 N s, harder than the replay trials'
2.5 N s, so that surviving 7 drawn worlds means surviving most others) are one rollout
batch, fallen robots stopped early; the fitness is the mean (or ``world_quantile``) of the K
values, the metrics their means.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from evomotion.core.checks import check_choice, check_fields, check_number
from evomotion.core.problem import Evaluation, GenomeSpec
from evomotion.errors import InputError
from evomotion.sim import nao
from evomotion.sim.backend import BatchedRollouts, make_simulator, validate_backend
from evomotion.sim.nao.joint_limits import SPEED_LIMITS
from evomotion.sim.nao.motion import Motion
from evomotion.sim.nao.replay import motion_targets
from evomotion.sim.rollout import ServoWork, fall_step, fell, torso_track
from evomotion.studies.humanoid_walk import gait
from evomotion.studies.humanoid_walk.walk_motion import assemble_poses, parts_batch, whole_walk

METRICS = ("time_to_fall_s", "forward_m", "speed_mps", "lateral_m", "heading_change_rad",
           "heading_deg_per_m", "cost_of_transport", "fell", "fall_rate", "speed_ratio")
GRAVITY = 9.81
NAO_TIMESTEP_S = 0.004  # models/nao_h25.xml, for the memory estimate before loading it
MAX_THREADS = 1024
#: the documented ranges of the ``[problem]`` floats besides those checked inline: the
#: weights (m per rad, m per m, m per unit), the heading tolerance (rad per m), the fall
#: height (m), the segment (s)
MAX_WEIGHT = 1000.0
MAX_HEADING_TOLERANCE_RAD_PER_M = 2 * math.pi
MAX_FALL_HEIGHT_M = 5.0
MAX_SEGMENT_S = 60.0


@dataclass(frozen=True)
class HumanoidWalkConfig:
    """The ``[problem]`` section of ``humanoid-walk``."""

    walk_s: float = 10.0  # steady walking at full amplitude (s), after the start-up ramp
    hold_s: float = 1.0  # the ready pose held after the stop (s), at least
    heading_weight: float = 1.0  # m lost per radian of turning
    lateral_weight: float = 1.0  # m lost per metre of sideways drift
    heading_tolerance_rad_per_m: float = 0.0873  # 5 degrees per metre walked ...
    excess_weight: float = 20.0  # ... each radian beyond costs this much more (m/rad)
    energy_weight: float = 0.05  # m lost per unit of cost of transport
    speed_margin: float = 1.0  # joint speeds allowed: this times the NAO motors' no-load speed
    fall_height_m: float = nao.FALL_HEIGHT_M
    fall_tilt_rad: float = nao.FALL_TILT_RAD
    worlds: int = 1  # K worlds per candidate: the nominal one and K - 1 perturbed (study: 8)
    world_seed: int = -1  # -1: the run's seed
    world_design: str = "latin"  # latin (strata cover every range) | random
    world_aggregate: str = "mean"  # mean | quantile
    world_quantile: float = 0.25
    #: the training worlds' lateral pushes, U(-p, p) N s: harder than the 2.5 N s of the
    #: replay trials, so that a walk that survives 7 drawn worlds survives most others
    train_push_ns: float = 3.5
    threads: int = 0  # mujoco.rollout threads; 0 = all cores
    backend: str = "cpu"  # physics: cpu (mujoco.rollout, float64) | warp (MuJoCo Warp, float32)
    warp_device: str = ""  # backend warp: "cuda:0", "cpu", ...; "" = the first GPU, else the CPU
    warp_deterministic: bool = True  # backend warp: MuJoCo Warp opt.deterministic = ALL
    warp_nconmax: int = 16  # backend warp: contacts per world to start with (grown when short)
    batch_rollouts: int = 2048  # rollouts simulated (and recorded in memory) at once
    segment_s: float = 0.4  # fallen robots stop being simulated at these boundaries (s)
    #: the robot: "" or "nao" (the NAO: the gait of gait.py through its leg IK), another
    #: bundled spec name (op3, dm-humanoid, dm-quadruped) or a spec .toml with a [gait]
    #: section (the joint-space gait of robot_gait.py)
    robot: str = ""

    def for_worker(self) -> HumanoidWalkConfig:
        return dataclasses.replace(self, threads=1) if self.threads == 0 else self

    def validate(self) -> None:
        check_fields(self, "problem")
        check_number("problem.walk_s", self.walk_s, lo=0.0, hi=600.0, lo_open=True)
        check_number("problem.hold_s", self.hold_s, lo=0.0, hi=60.0)
        for key in ("heading_weight", "lateral_weight", "excess_weight", "energy_weight"):
            check_number(f"problem.{key}", getattr(self, key), lo=0.0, hi=MAX_WEIGHT)
        check_number("problem.heading_tolerance_rad_per_m", self.heading_tolerance_rad_per_m,
                     lo=0.0, hi=MAX_HEADING_TOLERANCE_RAD_PER_M)
        check_number("problem.speed_margin", self.speed_margin, lo=0.0, hi=1.0, lo_open=True)
        check_number("problem.fall_height_m", self.fall_height_m, lo=0.0,
                     hi=MAX_FALL_HEIGHT_M, lo_open=True)
        check_number("problem.fall_tilt_rad", self.fall_tilt_rad, lo=0.0, hi=math.pi,
                     lo_open=True)
        check_number("problem.worlds", self.worlds, lo=1, hi=1024, integer=True)
        check_number("problem.world_seed", self.world_seed, lo=-1, integer=True)
        check_choice("problem.world_design", self.world_design, ("latin", "random"))
        check_choice("problem.world_aggregate", self.world_aggregate, ("mean", "quantile"))
        check_number("problem.world_quantile", self.world_quantile, lo=0.0, hi=1.0)
        check_number("problem.train_push_ns", self.train_push_ns, lo=0.0, hi=100.0)
        check_number("problem.threads", self.threads, lo=0, hi=MAX_THREADS, integer=True)
        validate_backend(self)
        check_number("problem.segment_s", self.segment_s, lo=0.0, hi=MAX_SEGMENT_S,
                     lo_open=True)

    def with_run_seed(self, seed: int) -> HumanoidWalkConfig:
        return dataclasses.replace(self, world_seed=seed) if self.world_seed < 0 else self

    def genome_dim(self) -> int:
        return len(gait.GENES)

    def horizon_s(self) -> float:
        """Length of every rollout: the longest schedule (slowest period) plus the hold."""
        s = gait.schedule(gait.UPPER[gait.INDEX["period_s"]], self.walk_s, self.hold_s)
        return s.total_ms / 1000.0

    memory_keys = ("walk_s", "hold_s", "worlds", "batch_rollouts")

    def memory_bytes(self, pop_size: int) -> int:
        """Recorded states of one batch of at most ``batch_rollouts`` rollouts (about 90
        doubles per physics step), twice."""
        steps = math.ceil(self.horizon_s() / NAO_TIMESTEP_S)
        return 2 * 8 * min(pop_size * self.worlds, self.batch_rollouts) * steps * 90


class HumanoidWalkProblem(BatchedRollouts):
    """Batch evaluation of gait parameters (fitness maximised)."""

    sense = "max"
    metric_names = METRICS

    def __init__(self, cfg: HumanoidWalkConfig | None = None) -> None:
        from evomotion.sim.robot import load_nao

        self.cfg = cfg = cfg or HumanoidWalkConfig()
        cfg.validate()
        self.robot = load_nao(cfg.robot, "RobotWalkProblem")  # model and initial states
        self.is_nao = True
        self.model = self.robot.model
        self.dt = float(self.model.opt.timestep)
        self.genome = GenomeSpec(gait.LOWER.copy(), gait.UPPER.copy(), names=gait.NAMES)
        self.horizon_s = cfg.horizon_s()
        self.nstep = int(math.ceil(self.horizon_s / self.dt))
        self.sim = make_simulator(self.model, cfg, cfg.threads)
        self.segment_steps = max(1, int(round(cfg.segment_s / self.dt)))
        m = self.model
        self.work = ServoWork(m)
        self.mass_kg = float(m.body_mass.sum())
        self.speed_limits = cfg.speed_margin * np.array([SPEED_LIMITS[j] for j in nao.JOINTS])
        self.worlds = None
        if cfg.worlds > 1:
            from evomotion.sim.nao.worlds import Perturbation, World, draw_worlds

            self.worlds = [World(m)] + draw_worlds(
                m, Perturbation(push_ns=(-cfg.train_push_ns, cfg.train_push_ns)), cfg.worlds - 1,
                np.random.default_rng(max(cfg.world_seed, 0)), self.horizon_s,
                design=cfg.world_design)

    def initial_population(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """The hand-set gait of :data:`.gait.DEFAULT` (a cautious walk; CMA-ES starts from
        its mean) and ``n - 1`` copies jittered by 5 % of each gene's range (for the GA)."""
        n = max(int(n), 1)
        span = self.genome.upper - self.genome.lower
        x = gait.DEFAULT + 0.05 * span * rng.standard_normal((n, span.size))
        x[0] = gait.DEFAULT
        return np.clip(x, self.genome.lower, self.genome.upper)

    def motion(self, genes: np.ndarray) -> Motion:
        """The whole walk of one genome (:func:`.walk_motion.whole_walk`)."""
        return whole_walk(genes, self.cfg.walk_s)

    def controls(self, genomes: np.ndarray) -> tuple[np.ndarray, ...]:
        """(first poses ``[P, 22]``, targets ``[P, nstep, 22]``, walk seconds ``[P]``, speed
        ratio ``[P]``), the targets by :func:`~evomotion.sim.nao.replay.motion_targets` of
        each genome's motion; the speed ratio is the fastest joint move between two key poses
        over ``speed_margin`` times that joint's motor limit (> 1: a real NAO cannot play it)."""
        P = len(genomes)
        first = np.empty((P, len(nao.JOINTS)))
        ctrl = np.empty((P, self.nstep, len(nao.JOINTS)))
        walk = np.empty(P)
        ratio = np.empty(P)
        periods = gait.period_ms(genomes[:, gait.INDEX["period_s"]])
        for p in np.unique(periods):
            rows = np.flatnonzero(periods == p)
            s = gait.schedule(p / 1000.0, self.cfg.walk_s, 0.0)
            start, cycle, stop = parts_batch(genomes[rows], s)
            q = assemble_poses(start, cycle, s.steady_ms // s.period_ms, stop)
            t = np.arange(q.shape[1], dtype=np.int64) * gait.POSE_MS
            ratio[rows] = (np.abs(np.diff(q, axis=1)).max(axis=1) / (gait.POSE_MS / 1000.0)
                           / self.speed_limits).max(axis=1)
            for r, qr in zip(rows, q, strict=True):
                first[r], ctrl[r] = motion_targets(Motion(nao.JOINTS, t, qr), self.dt,
                                                   self.nstep)
            walk[rows] = (s.walk_end_ms - s.ready_ms) / 1000.0
        return first, ctrl, walk, ratio

    def _initial_states(self, first: np.ndarray) -> np.ndarray:
        """One initial state per genome (every walk starts in the same crouch: one state per
        distinct first pose is computed)."""
        poses, inverse = np.unique(first, axis=0, return_inverse=True)
        states = np.stack([self.robot.state_at(f) for f in poses])
        return states[np.asarray(inverse).ravel()]

    def _fallen(self, states: np.ndarray) -> np.ndarray:
        return fell(states, self.cfg.fall_height_m, self.cfg.fall_tilt_rad)


    def _evaluate_batch(self, genomes: np.ndarray) -> Evaluation:
        genomes = np.atleast_2d(np.asarray(genomes, dtype=float))
        first, ctrl, walk, ratio = self.controls(genomes)
        init = self._initial_states(first)
        if self.worlds is None:
            states, _ = self.sim.run_until(init, ctrl, self._fallen, self.segment_steps)
            return self.score(states, ctrl, walk, ratio)
        return self._evaluate_worlds(init, ctrl, walk, ratio)

    def _evaluate_worlds(self, init: np.ndarray, ctrl: np.ndarray, walk: np.ndarray,
                         ratio: np.ndarray) -> Evaluation:
        from evomotion.sim.nao.worlds import aggregate_worlds, delayed_controls, simulate_worlds

        n, k = len(ctrl), len(self.worlds)
        c = np.repeat(ctrl, k, axis=0)  # genome-major: i * k + world
        states = simulate_worlds(self.worlds * n, np.repeat(init, k, axis=0), c,
                                 self.sim.nthread, stopped=self._fallen,
                                 segment_steps=self.segment_steps, simulator=self.sim)
        lat = np.tile([w.latency_steps for w in self.worlds], n)
        ev = self.score(states, delayed_controls(c, lat), np.repeat(walk, k),
                        np.repeat(ratio, k))
        return aggregate_worlds(ev, n, k, self.cfg.world_aggregate, self.cfg.world_quantile)

    def score(self, states: np.ndarray, ctrl: np.ndarray, walk_s: np.ndarray,
              speed_ratio: np.ndarray) -> Evaluation:
        """Fitness and metrics from recorded ``states[P, nstep, nstate]``, the targets the
        servos received ``ctrl[P, nstep, 22]``, the walk time and the speed ratio."""
        c = self.cfg
        track = torso_track(states)
        fall = fall_step(track, c.fall_height_m, c.fall_tilt_rad)
        fell = fall < self.nstep
        last = np.minimum(fall, self.nstep - 1)
        rows = np.arange(len(states))
        d = track.xyz[rows, last, :2] - track.xyz[:, 0, :2]
        forward, lateral = d[:, 0], d[:, 1]
        heading = track.yaw_rad[rows, last] - track.yaw_rad[:, 0]
        t_up = np.where(fell, (fall + 1) * self.dt, self.nstep * self.dt)
        work = self.work(states, ctrl, last)  # mechanical work of the servos (J)
        cot = work / (self.mass_kg * GRAVITY * np.maximum(forward, 0.1))
        heading_abs = np.abs(heading)
        quality = forward - c.heading_weight * heading_abs - c.lateral_weight * np.abs(lateral) \
            - c.excess_weight * np.maximum(
                heading_abs - c.heading_tolerance_rad_per_m * np.maximum(forward, 0.0), 0.0) \
            - c.energy_weight * cot
        too_fast = speed_ratio > 1.0
        fitness = np.where(fell, np.minimum(t_up + 0.1 * np.clip(forward, -0.5, 0.5),
                                            self.horizon_s - 1e-3),
                           np.where(too_fast, self.horizon_s + 0.5 - 0.49 * np.tanh(
                               speed_ratio - 1.0), self.horizon_s + 1.0 + soft_floor(quality)))
        metrics = {
            "time_to_fall_s": t_up, "forward_m": forward, "speed_mps": forward / walk_s,
            "lateral_m": lateral, "heading_change_rad": heading,
            "heading_deg_per_m": np.degrees(heading_abs) / np.maximum(forward, 0.01),
            "cost_of_transport": cot, "fell": fell.astype(float),
            "fall_rate": fell.astype(float), "speed_ratio": np.asarray(speed_ratio, float),
        }
        return Evaluation(fitness, metrics)


def soft_floor(quality: np.ndarray) -> np.ndarray:
    """``quality`` where positive, else ``-0.99 (1 - exp(quality))``: strictly increasing and
    above -0.99, so a standing robot never scores below one that fell, and a worse walk always
    scores lower (no clipping)."""
    q = np.asarray(quality, dtype=float)
    return np.where(q >= 0.0, q, -0.99 * -np.expm1(np.minimum(q, 0.0)))


def make_problem(cfg: HumanoidWalkConfig):
    """The NAO walk, or with ``cfg.robot`` the joint-space gait of another robot."""
    if not isinstance(cfg, HumanoidWalkConfig):
        raise InputError("humanoid-walk: expected a HumanoidWalkConfig")
    from evomotion.sim.robot import is_nao

    if not is_nao(cfg.robot):
        from evomotion.studies.humanoid_walk.robot_walk import RobotWalkProblem

        return RobotWalkProblem(cfg)
    return HumanoidWalkProblem(cfg)
