"""The walk problem: evaluate a batch of gaits on one robot, the robot a parameter.

The robot is ``problem.robot`` (the NAO by default; :mod:`evomotion.sim.robots`), its gait the
one its capabilities allow (:mod:`.gaits`): on the NAO the foot-placement walk of
:mod:`.foot_gait`, each genome decoded into key poses every 20 ms (start-up, ramps, steady
cycles for ``walk_s`` seconds, stop) and those into one servo target per physics step by
exactly the linear interpolation :func:`evomotion.sim.robots.nao.replay.motion_targets`
applies to a ``.motion``, so the exported ``best.motion`` replayed with ``evomotion replay
--hold H`` is the evaluated rollout; on any other robot the joint-space oscillators of
:mod:`.joint_gait` on its spec's ``[gait]`` roles. Every rollout lasts ``horizon_s`` (the
longest walk the period bounds allow, plus ``hold_s``); shorter walks hold their last pose to
the end. Fallen robots stop being simulated at ``segment_s`` boundaries.

Fitness (maximised; units in brackets), like humanoid-step's it ranks every robot that stays
up above every robot that falls and never saturates:

- fell: ``time_up_s`` [s] ``+ 0.1 clip(forward_m, -0.5, 0.5)``, below ``horizon_s``;
- stayed up: ``horizon_s + 1 + soft_floor(quality_m)`` (:func:`soft_floor`),
  ``quality_m = forward_m - heading_weight |heading_change_rad| - lateral_weight
  |lateral_m| - excess_weight max(|heading_change_rad| - heading_tolerance_rad_per_m
  max(forward_m, 0), 0) - energy_weight cost_of_transport`` [m]: forward torso
  displacement over the walk, penalised by turning (1 m/rad), sideways drift (1 m/m),
  turning beyond 5 degrees per metre walked (20 m/rad more) and the cost of transport
  (mechanical work ``sum |tau qdot| dt`` of the joint servos over ``m g forward``; ``tau =
  clip(kp (target - q), force range)``, the position servo of the model; actuators on
  tendons count no work; 0.05 m per unit). Displacements are measured in the robot's start
  frame (rotated by its start yaw; the NAO starts at yaw 0, so this is its world frame).
- stayed up but too fast for the real robot (a robot with motor ``speed_limits``: a joint
  moves faster between two key poses than ``speed_margin`` times its motor's no-load speed,
  :data:`~evomotion.sim.robots.nao.joint_limits.SPEED_LIMITS`): ``horizon_s + 0.5 - 0.49
  tanh(speed_ratio - 1)``, between the fallen and the playable walks, so the best walk can
  always be exported to the real robot.

The joint-space gait adds ``straightness``: the forward displacement over the torso's path
length sampled once per gait cycle (1: a straight line).

Perturbed worlds (``worlds = K``: the nominal world and K - 1 drawn from the run seed, by
default as a Latin hypercube over the ranges of :class:`~evomotion.sim.worlds.Perturbation`,
pushes during the walk of up to ``train_push_ns`` = 3.5 N s, harder than the replay trials'
2.5 N s, so that surviving 7 drawn worlds means surviving most others; scaled by the robot's
mass for another robot, :meth:`~evomotion.sim.worlds.Perturbation.for_mass`) are one rollout
batch, fallen robots stopped early; the fitness is the mean (or ``world_quantile``) of the K
values, the metrics their means.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from evomotion.core.checks import check_choice, check_fields, check_number
from evomotion.core.problem import Evaluation, Sense
from evomotion.errors import InputError
from evomotion.sim.backend import BatchedRollouts, make_simulator
from evomotion.sim.motion import Motion
from evomotion.sim.physics_config import PerturbedWorldsConfig, PhysicsConfig, validate_physics
from evomotion.sim.robots import nao
from evomotion.sim.rollout import ServoWork, fall_step, fell, torso_track
from evomotion.studies.humanoid_walk import foot_gait
from evomotion.studies.humanoid_walk.gaits import FootPlacementGait, GaitBatch, gait_for

METRICS = FootPlacementGait.metric_names  # the NAO's; another robot's: its gait's
GRAVITY = 9.81
NAO_TIMESTEP_S = 0.004  # robots/nao/nao_h25.xml, for the memory estimate before loading it
#: the documented ranges of the ``[problem]`` floats besides those checked inline: the
#: weights (m per rad, m per m, m per unit), the heading tolerance (rad per m), the fall
#: height (m)
MAX_WEIGHT = 1000.0
MAX_HEADING_TOLERANCE_RAD_PER_M = 2 * math.pi
MAX_FALL_HEIGHT_M = 5.0


@dataclass(frozen=True)
class WalkKeys:
    """The walk's own keys of ``[problem]`` (first in ``config.toml``; the physics and the
    other world keys are :mod:`evomotion.sim.physics_config`'s)."""

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
    world_design: str = "latin"  # drawn worlds: latin (strata cover every range) | random
    #: the training worlds' lateral pushes, U(-p, p) N s: harder than the 2.5 N s of the
    #: replay trials, so that a walk that survives 7 drawn worlds survives most others
    train_push_ns: float = 3.5


@dataclass(frozen=True)
class HumanoidWalkConfig(PhysicsConfig, PerturbedWorldsConfig, WalkKeys):
    """The ``[problem]`` section of ``humanoid-walk-open-loop``: its own keys
    (:class:`WalkKeys`), the
    perturbed worlds' (the study sets ``worlds = 8``) and the physics'
    (:mod:`evomotion.sim.physics_config`), the robot."""

    #: the robot: "" or "nao" (the NAO: its capabilities give it the foot-placement gait of
    #: foot_gait.py), another bundled spec name (op3, dm-humanoid, dm-quadruped) or a spec
    #: .toml with a [gait] section (the joint-space gait of joint_gait.py; gaits.py chooses)
    robot: str = ""

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
        check_choice("problem.world_design", self.world_design, ("latin", "random"))
        check_number("problem.train_push_ns", self.train_push_ns, lo=0.0, hi=100.0)
        validate_physics(self)

    def genome_dim(self) -> int:
        return len(foot_gait.GENES)

    def horizon_s(self) -> float:
        """Length of every rollout: the longest schedule (slowest period) plus the hold."""
        s = foot_gait.schedule(foot_gait.UPPER[foot_gait.INDEX["period_s"]], self.walk_s,
                               self.hold_s)
        return s.total_ms / 1000.0

    memory_keys = ("walk_s", "hold_s", "worlds", "batch_rollouts")

    def memory_bytes(self, pop_size: int) -> int:
        """Recorded states of one batch of at most ``batch_rollouts`` rollouts (about 90
        doubles per physics step), twice."""
        steps = math.ceil(self.horizon_s() / NAO_TIMESTEP_S)
        return 2 * 8 * min(pop_size * self.worlds, self.batch_rollouts) * steps * 90


class HumanoidWalkProblem(BatchedRollouts):
    """Batch evaluation of the gaits of one robot (fitness maximised): the robot of
    ``cfg.robot`` (the NAO by default), driven by the gait its capabilities allow
    (:func:`.gaits.gait_for`)."""

    sense: Sense = "max"
    metric_names: tuple[str, ...] = METRICS  # the instance's: its gait's (:mod:`.gaits`)

    def __init__(self, cfg: HumanoidWalkConfig | None = None) -> None:
        from evomotion.sim.robots import load_robot

        self.cfg = cfg = cfg or HumanoidWalkConfig()
        cfg.validate()
        r = self.robot = load_robot(cfg.robot or "nao")
        self.model = m = r.model
        self.dt = float(m.opt.timestep)
        self.gait = gait_for(r, cfg, self.dt)
        self.kind = self.gait.kind
        self.metric_names = self.gait.metric_names
        self.genome = self.gait.genome
        self.horizon_s = self.gait.horizon_s
        self.nstep = int(math.ceil(self.horizon_s / self.dt))
        self.sim = make_simulator(m, cfg, cfg.threads)
        self.segment_steps = max(1, int(round(cfg.segment_s / self.dt)))
        servos = self.gait.work_servos  # None: every actuator; else these columns
        self.work = None if servos is not None and not servos.size else ServoWork(m, servos)
        self.mass_kg = float(m.body_mass.sum())
        self.fall_height_m, self.fall_tilt_rad = r.fall_thresholds(cfg.fall_height_m,
                                                                   cfg.fall_tilt_rad)
        self.worlds = None
        if cfg.worlds > 1:
            from evomotion.sim.worlds import Perturbation, World, draw_worlds

            push = Perturbation(push_ns=(-cfg.train_push_ns, cfg.train_push_ns))
            self.worlds = [World(m)] + draw_worlds(
                m, push.for_mass(r.mass_kg), cfg.worlds - 1,
                np.random.default_rng(max(cfg.world_seed, 0)), self.horizon_s,
                design=cfg.world_design)

    def initial_population(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """The gait's hand-set default (a cautious walk; CMA-ES starts from its mean) and
        ``n - 1`` copies jittered by 5 % of each gene's range (for the GA)."""
        n = max(int(n), 1)
        span = self.genome.upper - self.genome.lower
        x = self.gait.default + 0.05 * span * rng.standard_normal((n, span.size))
        x[0] = self.gait.default
        return np.clip(x, self.genome.lower, self.genome.upper)

    def motion(self, genes: np.ndarray) -> Motion:
        """The whole walk of one genome as a motion of the robot's joints."""
        return self.gait.motion(genes)

    def _fallen(self, states: np.ndarray) -> np.ndarray:
        return fell(states, self.fall_height_m, self.fall_tilt_rad)

    def simulate(self, genomes: np.ndarray) -> tuple[np.ndarray, GaitBatch]:
        """(recorded states, the decoded batch) of ``genomes`` in the nominal world."""
        b = self.gait.batch(np.atleast_2d(np.asarray(genomes, dtype=float)), self.nstep)
        states, _ = self.sim.run_until(b.init, b.ctrl, self._fallen, self.segment_steps)
        return states, b

    def _evaluate_batch(self, genomes: np.ndarray) -> Evaluation:
        genomes = np.atleast_2d(np.asarray(genomes, dtype=float))
        if self.worlds is None:
            states, b = self.simulate(genomes)
            return self.score(states, b.ctrl, b)
        b = self.gait.batch(genomes, self.nstep)
        from evomotion.sim.worlds import aggregate_worlds, delayed_controls, simulate_worlds

        n, k = len(genomes), len(self.worlds)
        c = np.repeat(b.ctrl, k, axis=0)  # genome-major: i * k + world
        init = b.init if b.init.ndim == 1 else np.repeat(b.init, k, axis=0)
        w_states = simulate_worlds(self.worlds * n, init, c, self.sim.nthread,
                                   stopped=self._fallen, segment_steps=self.segment_steps,
                                   simulator=self.sim)
        assert isinstance(w_states, np.ndarray)  # without sensors: the states alone
        lat = np.tile([w.latency_steps for w in self.worlds], n)
        speed, period = (None if v is None else np.repeat(v, k)
                         for v in (b.speed_ratio, b.period_s))
        per_world = GaitBatch(init, c, np.repeat(b.walk_s, k), speed, period)
        ev = self.score(w_states, delayed_controls(c, lat), per_world)
        return aggregate_worlds(ev, n, k, self.cfg.world_aggregate, self.cfg.world_quantile)

    def score(self, states: np.ndarray, ctrl: np.ndarray, b: GaitBatch) -> Evaluation:
        """Fitness and metrics from recorded ``states[P, nstep, nstate]``, the targets the
        servos received ``ctrl[P, nstep, nu]`` and the batch's walk seconds, speed ratio and
        period (:class:`.gaits.GaitBatch`). Displacements are in the robot's start frame
        (rotated by its start yaw)."""
        c = self.cfg
        track = torso_track(states)
        fall = fall_step(track, self.fall_height_m, self.fall_tilt_rad)
        fell_ = fall < self.nstep
        last = np.minimum(fall, self.nstep - 1)
        rows = np.arange(len(states))
        yaw0 = track.yaw_rad[:, 0]
        d = track.xyz[rows, last, :2] - track.xyz[:, 0, :2]
        forward = np.cos(yaw0) * d[:, 0] + np.sin(yaw0) * d[:, 1]
        lateral = -np.sin(yaw0) * d[:, 0] + np.cos(yaw0) * d[:, 1]
        heading = track.yaw_rad[rows, last] - yaw0
        t_up = np.where(fell_, (fall + 1) * self.dt, self.nstep * self.dt)
        work = self.work(states, ctrl, last) if self.work is not None else np.zeros(len(rows))
        cot = work / (self.mass_kg * GRAVITY * np.maximum(forward, 0.1))
        h = np.abs(heading)
        quality = forward - c.heading_weight * h - c.lateral_weight * np.abs(lateral) \
            - c.excess_weight * np.maximum(h - c.heading_tolerance_rad_per_m
                                           * np.maximum(forward, 0.0), 0.0) \
            - c.energy_weight * cot
        up = self.horizon_s + 1.0 + soft_floor(quality)
        if b.speed_ratio is not None:  # too fast for the real motors: below every playable walk
            up = np.where(b.speed_ratio > 1.0,
                          self.horizon_s + 0.5 - 0.49 * np.tanh(b.speed_ratio - 1.0), up)
        fitness = np.where(fell_, np.minimum(t_up + 0.1 * np.clip(forward, -0.5, 0.5),
                                             self.horizon_s - 1e-3), up)
        metrics = {"time_to_fall_s": t_up, "forward_m": forward,
                   "speed_mps": forward / b.walk_s, "lateral_m": lateral,
                   "heading_change_rad": heading,
                   "heading_deg_per_m": np.degrees(h) / np.maximum(forward, 0.01),
                   "cost_of_transport": cot, "fell": fell_.astype(float),
                   "fall_rate": fell_.astype(float)}
        if b.speed_ratio is not None:
            metrics["speed_ratio"] = np.asarray(b.speed_ratio, float)
        if b.period_s is not None:
            stride = np.maximum(np.round(np.asarray(b.period_s) / self.dt).astype(np.int64), 1)
            metrics["straightness"] = straightness(track.xyz[:, :, :2], last, stride, forward)
        return Evaluation(fitness, {k: metrics[k] for k in self.metric_names})


def straightness(xy: np.ndarray, last: np.ndarray, stride: np.ndarray,
                 forward: np.ndarray) -> np.ndarray:
    """Forward displacement over the length of the torso's path sampled once per gait cycle
    (``stride[P]`` steps, so the sway within a cycle does not count), up to step ``last[P]``:
    1 for a straight walk, less for a curved or zig-zag one, 0 for no progress."""
    out = np.zeros(len(xy))
    for s in np.unique(stride):
        rows = np.flatnonzero(stride == s)
        pts = xy[rows][:, ::s]  # [r, K, 2]
        k = np.arange(pts.shape[1])[None]
        seg = np.linalg.norm(np.diff(pts, axis=1), axis=2)  # [r, K-1]
        seg = seg * (k[:, 1:] * s <= last[rows, None])
        length = seg.sum(axis=1)
        out[rows] = np.where(length > 1e-6, np.maximum(forward[rows], 0.0)
                             / np.maximum(length, 1e-6), 0.0)  # no path: no progress
    return np.clip(out, 0.0, 1.0)


def soft_floor(quality: np.ndarray) -> np.ndarray:
    """``quality`` where positive, else ``-0.99 (1 - exp(quality))``: strictly increasing and
    above -0.99, so a standing robot never scores below one that fell, and a worse walk always
    scores lower (no clipping)."""
    q = np.asarray(quality, dtype=float)
    return np.where(q >= 0.0, q, -0.99 * -np.expm1(np.minimum(q, 0.0)))


def make_problem(cfg: HumanoidWalkConfig) -> HumanoidWalkProblem:
    """The walk of ``cfg.robot`` (the NAO by default)."""
    if not isinstance(cfg, HumanoidWalkConfig):
        raise InputError("humanoid-walk-open-loop: expected a HumanoidWalkConfig")
    return HumanoidWalkProblem(cfg)
