"""The forward-step problem of paper 000: evaluate a batch of leg trajectories on the NAO.

Each genome is decoded (see :mod:`.encoding`) into targets for the 10 leg servos on every
physics step of ``motion_s + hold_s`` seconds; the other 12 servos hold the initial pose.
The whole batch is rolled out with ``mujoco.rollout`` (threads = ``threads``) and scored from
the recorded torso states, the sole positions and the sole-floor contacts.

``fitness = "step"`` (the default; maximised; units in brackets) ranks robots that stay up
through the motion *and* the hold (``hold_s`` >= 2 s by default) above every robot that falls,
and among those it never saturates:

- fell: ``time_up_s`` [s] ``+ 0.1 clip(forward_m, -0.1, 0.1)``, at most ``motion_s + hold_s``;
- stayed up: ``motion_s + hold_s + 1 + max(quality_m, -0.99)`` with
  ``quality_m = forward_m - heading_weight |heading_change_rad| - lateral_weight |lateral_m|
  - flight_weight flight_s`` [m]: forward progress of the feet, penalised by turning
  (``heading_weight`` m/rad, 0.5: a 60° turn costs 0.52 m), lateral drift (``lateral_weight``,
  2 m/m) and flight phases (``flight_weight`` m/s, 2: time with neither sole on the floor, in
  gaps of at least 12 ms), and ``excess_weight`` (5) more per radian or metre beyond the
  tolerances ``heading_tolerance_rad`` (5°) and ``lateral_tolerance_m`` (2 cm) that a straight
  step must meet (and per second of flight), plus ``step_bonus_m`` (0.05 m) once the feet are
  ``step_min_m`` (5 cm) forward.

``fitness = "paper"`` is the paper's literal one (``--preset paper``; ``"seed"`` is its old name):
``time_to_fall_s + distance_weight * clip(forward_m, -forward_cap_m, forward_cap_m)``
(seconds, ``distance_weight`` = 10 s/m, ``forward_cap_m`` = 0.2 m), which saturates at
``motion_s + hold_s + 2`` and rewards turning and hopping steps as much as straight ones.

- ``time_to_fall_s``: time of the first fallen state (torso origin below ``fall_height_m`` or
  its up axis tilted more than ``fall_tilt_rad``), or the full ``motion_s + hold_s``;
- ``forward_m`` / ``lateral_m``: displacement along +x (the initial heading) / +y of the
  midpoint of the two sole centres, at the end or at the fall: leaning or diving earns nothing;
- ``heading_change_rad``: the torso's yaw change; ``flight_s``: time with neither sole touching
  the floor (MuJoCo contact sensors on the sole geoms).
A *step* (metric ``stepped``) is ``forward_m >= step_min_m`` (5 cm) without falling.

Rollouts run in segments of ``segment_s``; robots that have fallen are not simulated further
(their remaining states repeat the fallen state), which saves most of the physics early in a
run when nearly every individual falls.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from evomotion.core.checks import check_choice, check_fields, check_number
from evomotion.core.problem import Evaluation, Sense
from evomotion.errors import InputError
from evomotion.sim.backend import BatchedRollouts, make_simulator
from evomotion.sim.physics_config import PerturbedWorldsConfig, PhysicsConfig, validate_physics
from evomotion.sim.robots import nao
from evomotion.sim.rollout import fall_step, fell, torso_track
from evomotion.studies.humanoid_step.encoding import ENCODINGS, ServoEncoding

#: Paper 000, Table 1: servo angle limits (rad) used as GA bounds.
PAPER_TABLE1: dict[str, tuple[float, float]] = {
    "LKneePitch": (0.0, 2.2689), "RKneePitch": (0.0, 2.2689),
    "LAnkleRoll": (-0.7854, 0.4363), "RAnkleRoll": (-0.4363, 0.7854),
    "LHipRoll": (-0.4363, 0.7854), "RHipRoll": (-0.7854, 0.4363),
    "LAnklePitch": (-1.309, 0.7854), "RAnklePitch": (-1.309, 0.7854),
    "LHipPitch": (-1.7453, 0.4363), "RHipPitch": (-1.7453, 0.4363),
}
METRICS = ("time_to_fall_s", "forward_m", "lateral_m", "heading_change_rad", "flight_s", "fell",
           "stepped", "fall_rate")
FITNESSES = ("step", "paper")
#: Old names of fitnesses: ``"seed"`` is the old name of ``"paper"`` (run folders written before
#: issue 32 record it, and they load and resume unchanged).
OLD_FITNESS_NAMES = {"seed": "paper"}
#: a flight phase is at least this many consecutive physics steps (12 ms) with neither sole on
#: the floor; shorter gaps are contact flicker at touch-down, not a hop
FLIGHT_MIN_STEPS = 3
#: ``problem.intervals`` at most
MAX_INTERVALS = 10_000
#: the NAO model's physics step (``robots/nao/nao_h25.xml``), for estimates before it is loaded
NAO_TIMESTEP_S = 0.004
#: doubles recorded per individual and physics step: state (58), sensors, controls (22),
#: leg targets, rounded up
ROLLOUT_DOUBLES_PER_STEP = 100


@dataclass(frozen=True)
class StepKeys:
    """The step's own keys of ``[problem]`` (first in ``config.toml``; the physics and world
    keys are :mod:`evomotion.sim.physics_config`'s)."""

    encoding: str = "linear"  # linear | spline | harmonic
    intervals: int = 20  # K time intervals of the step (paper: 20)
    motion_s: float = 2.0  # duration of the step motion T (s)
    hold_s: float = 2.0  # initial pose held after the motion (s; paper: 1)
    fitness: str = "step"  # step (module doc) | paper (the paper's literal one; old name: seed)
    heading_weight: float = 0.5  # step fitness: metres lost per radian of turning (m/rad)
    lateral_weight: float = 2.0  # step fitness: metres lost per metre of lateral drift
    flight_weight: float = 2.0  # step fitness: metres lost per second without a sole down (m/s)
    heading_tolerance_rad: float = 0.0873  # step fitness: beyond 5 degrees of turning ...
    lateral_tolerance_m: float = 0.02  # ... or 2 cm of lateral drift ...
    excess_weight: float = 5.0  # ... each extra radian / metre (or second of flight) costs
    step_bonus_m: float = 0.05  # step fitness: credit for feet >= step_min_m forward (m)
    distance_weight: float = 10.0  # paper fitness: fitness per metre forward (s/m)
    forward_cap_m: float = 0.2  # paper fitness: forward distance credited at most (m)
    fall_height_m: float = nao.FALL_HEIGHT_M
    fall_tilt_rad: float = nao.FALL_TILT_RAD  # 45 degrees
    step_min_m: float = 0.05
    bounds_scale: float = 1.0  # 1 = the paper's Table 1 (intersected with the model ranges)


@dataclass(frozen=True)
class HumanoidStepConfig(PhysicsConfig, PerturbedWorldsConfig, StepKeys):
    """The ``[problem]`` section of ``humanoid-step``: its own keys (:class:`StepKeys`), the
    perturbed worlds' and the physics' (:mod:`evomotion.sim.physics_config`), the robot."""

    segment_s: float = 0.2  # fallen robots stop being simulated at these boundaries (s)
    #: the robot: "" or "nao" (the NAO, sim/robots/nao/nao.toml), another bundled spec name
    #: (dm-humanoid, op3) or a spec .toml (sim/robot); its [evolve] joints make the step, its
    #: [fall] thresholds apply unless fall_height_m / fall_tilt_rad are set to other values
    #: than the NAO's defaults
    robot: str = ""

    def validate(self) -> None:
        """One-line :class:`InputError` for impossible settings (see :func:`validate`)."""
        validate(self)

    def genome_dim(self) -> int:
        """The genome's length (for the memory check before the problem is built)."""
        n = len(nao.LEG_SERVOS)
        return 3 * n + 1 if self.encoding == "harmonic" else n * (self.intervals - 1)

    #: what memory_bytes depends on (for its message)
    memory_keys = ("motion_s", "hold_s", "worlds", "batch_rollouts")

    def memory_bytes(self, pop_size: int) -> int:
        """Bytes of one batch's rollout: recorded states, sensors and controls (doubles) of
        every physics step of the motion and the hold, twice (analysis temporaries)."""
        steps = math.ceil((self.motion_s + self.hold_s) / NAO_TIMESTEP_S)
        rollouts = min(pop_size * self.worlds, self.batch_rollouts)
        return 2 * 8 * rollouts * steps * ROLLOUT_DOUBLES_PER_STEP


def servo_bounds(model, scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """The paper's Table 1 intersected with the model's joint ranges for ``nao.LEG_SERVOS``; with
    ``scale < 1`` each interval shrinks towards the initial pose by that factor."""
    rng = nao.joint_ranges(model, nao.LEG_SERVOS)
    t1 = np.array([PAPER_TABLE1[n] for n in nao.LEG_SERVOS])
    lo, hi = np.maximum(rng[:, 0], t1[:, 0]), np.minimum(rng[:, 1], t1[:, 1])
    q0 = leg_initial_pose()
    return q0 + scale * (lo - q0), q0 + scale * (hi - q0)


def leg_initial_pose() -> np.ndarray:
    return nao.pose_vector()[nao.joint_columns(nao.LEG_SERVOS)]


#: the documented ranges of the ``[problem]`` floats: weights (m per rad, per m, per s;
#: s per m), lengths (m), tolerances, times (s), the fall height (m)
MAX_WEIGHT = 1000.0
MAX_LENGTH_M = 10.0
MAX_FALL_HEIGHT_M = 5.0
MAX_TIME_S = 60.0


def fitness_name(name: object) -> object:
    """The fitness ``name`` under its name now (:data:`OLD_FITNESS_NAMES`)."""
    return OLD_FITNESS_NAMES.get(name, name) if isinstance(name, str) else name


def validate(cfg: HumanoidStepConfig) -> None:
    """One-line :class:`InputError` for impossible settings: every float finite and within
    its documented range (the constants above; the physics and world keys':
    :func:`~evomotion.sim.physics_config.validate_physics`)."""
    check_fields(cfg, "problem")
    check_choice("problem.encoding", cfg.encoding, ENCODINGS)
    check_choice("problem.fitness", fitness_name(cfg.fitness), FITNESSES)
    validate_physics(cfg)
    for key in ("heading_weight", "lateral_weight", "flight_weight", "excess_weight",
                "distance_weight"):
        check_number(f"problem.{key}", getattr(cfg, key), lo=0.0, hi=MAX_WEIGHT)
    check_number("problem.heading_tolerance_rad", cfg.heading_tolerance_rad, lo=0.0,
                 hi=math.pi)
    for key in ("lateral_tolerance_m", "step_bonus_m", "step_min_m"):
        check_number(f"problem.{key}", getattr(cfg, key), lo=0.0, hi=MAX_LENGTH_M)
    check_number("problem.forward_cap_m", cfg.forward_cap_m, lo=0.0, hi=MAX_LENGTH_M,
                 lo_open=True)
    check_number("problem.intervals", cfg.intervals, lo=2, hi=MAX_INTERVALS, integer=True)
    check_number("problem.fall_height_m", cfg.fall_height_m, lo=0.0, hi=MAX_FALL_HEIGHT_M,
                 lo_open=True)
    check_number("problem.fall_tilt_rad", cfg.fall_tilt_rad, lo=0.0, hi=math.pi, lo_open=True)
    check_number("problem.motion_s", cfg.motion_s, lo=0.0, hi=MAX_TIME_S, lo_open=True)
    check_number("problem.hold_s", cfg.hold_s, lo=0.0, hi=MAX_TIME_S)
    check_number("problem.bounds_scale", cfg.bounds_scale, lo=0.0, hi=1.0, lo_open=True)


def flight_steps(airborne: np.ndarray, min_run: int) -> np.ndarray:
    """Per row, the number of True entries of ``airborne[pop, nstep]`` that lie in runs of at
    least ``min_run`` consecutive Trues (vectorised run lengths)."""
    a = np.pad(airborne.astype(np.int8), ((0, 0), (1, 1)))
    d = np.diff(a, axis=1)
    rows_s, starts = np.nonzero(d == 1)
    _, ends = np.nonzero(d == -1)  # row-major: the i-th end closes the i-th start
    length = ends - starts
    out = np.zeros(airborne.shape[0], dtype=np.int64)
    np.add.at(out, rows_s, np.where(length >= min_run, length, 0))
    return out


class HumanoidStepProblem(BatchedRollouts):
    """Batch evaluation of forward-step trajectories (fitness maximised)."""

    sense: Sense = "max"
    metric_names: tuple[str, ...] = METRICS

    def __init__(self, cfg: HumanoidStepConfig | None = None) -> None:
        self.cfg = cfg = cfg or HumanoidStepConfig()
        validate(cfg)
        self._init_robot(cfg)
        self.dt = float(self.model.opt.timestep)
        self.nstep = int(round((cfg.motion_s + cfg.hold_s) / self.dt))
        self.t_step = self.dt * np.arange(self.nstep)  # target applied during step i
        self.segment_steps = max(1, int(round(cfg.segment_s / self.dt)))
        self.sim = make_simulator(self.model, cfg, cfg.threads)
        self.worlds = None
        if cfg.worlds > 1:  # the nominal world and K - 1 drawn ones
            from evomotion.sim.worlds import Perturbation, World, draw_worlds

            self.worlds = [World(self.model)] + draw_worlds(
                self.model, Perturbation().for_mass(self.robot.mass_kg), cfg.worlds - 1,
                np.random.default_rng(max(cfg.world_seed, 0)), cfg.motion_s)

    def _init_robot(self, cfg: HumanoidStepConfig) -> None:
        """The robot of its spec (:mod:`evomotion.sim.robots`; the NAO's, ``nao.toml``, by
        default): its ``[evolve]`` joints and ranges (shrunk towards the initial pose by
        ``bounds_scale``; the NAO's are the paper's Table 1 within its model's ranges), feet
        ``left`` and ``right``, ``[fall]`` thresholds. A robot with the ``webots_names`` and
        ``naoqi_export`` capabilities (the NAO) also gets the NAO's replay and exports."""
        from evomotion.sim.robots import load_robot

        r = self.robot = load_robot(cfg.robot or "nao")
        if set(r.feet) != {"left", "right"}:
            raise InputError(f"problem.robot: {r.name} has feet {', '.join(r.feet)}; a step "
                             "needs a biped with feet 'left' and 'right'")
        if not r.evolved:
            raise InputError(f"problem.robot: {r.spec.path} has no [evolve] joints")
        self.model = r.model
        q0 = r.pose[r.columns]
        lo = q0 + cfg.bounds_scale * (np.minimum(r.lower, q0) - q0)
        hi = q0 + cfg.bounds_scale * (np.maximum(r.upper, q0) - q0)
        self.encoding = ServoEncoding(cfg.encoding, q0, lo, hi, cfg.intervals, cfg.motion_s)
        self.genome = self.encoding.genome(r.evolved)
        self.leg_columns = r.columns
        self.base = r.pose
        self.state0 = r.state0
        data0 = mujoco.MjData(self.model)
        mujoco.mj_setState(self.model, data0, self.state0, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        data0.ctrl[:] = r.pose
        mujoco.mj_forward(self.model, data0)
        self.sole_columns = [r.sensor("left_pos"), r.sensor("right_pos")]
        self.sole0 = 0.5 * (data0.sensordata[self.sole_columns[0]]
                            + data0.sensordata[self.sole_columns[1]])
        self.contact_columns = [r.sensor("left_floor").start, r.sensor("right_floor").start]
        self.fall_height_m, self.fall_tilt_rad = r.fall_thresholds(cfg.fall_height_m,
                                                                   cfg.fall_tilt_rad)

    def controls(self, genomes: np.ndarray, t: np.ndarray | None = None) -> np.ndarray:
        """Actuator targets ``[pop, nstep, 22]`` for a batch of genomes."""
        t = self.t_step if t is None else t
        legs = self.encoding.targets(genomes, t)
        ctrl = np.broadcast_to(self.base, (legs.shape[0], legs.shape[1], self.base.size)).copy()
        ctrl[:, :, self.leg_columns] = legs
        return ctrl

    def _fallen(self, states: np.ndarray) -> np.ndarray:
        return fell(states, self.fall_height_m, self.fall_tilt_rad)

    def simulate(self, genomes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Recorded (states, sole positions) of a batch, fallen robots stopped early."""
        return self.sim.run_until(self.state0, self.controls(genomes), self._fallen,
                                  self.segment_steps)

    def score(self, states: np.ndarray, sensors: np.ndarray) -> Evaluation:
        """Fitness and metrics from recorded states ``[pop, nstep, nstate]`` and sensors."""
        c = self.cfg
        track = torso_track(states)
        fall = fall_step(track, self.fall_height_m, self.fall_tilt_rad)
        fell = fall < self.nstep
        last = np.minimum(fall, self.nstep - 1)
        rows = np.arange(states.shape[0])
        soles = sensors[rows, last]
        left, right = (soles[:, cols][:, :2] for cols in self.sole_columns)
        end = 0.5 * (left + right)
        t_fall = np.where(fell, (fall + 1) * self.dt, self.nstep * self.dt)
        forward, lateral = end[:, 0] - self.sole0[0], end[:, 1] - self.sole0[1]
        heading = track.yaw_rad[rows, last] - track.yaw_rad[:, 0]
        down = (sensors[:, :, self.contact_columns] > 0.5).any(axis=2)  # [pop, nstep]
        # from the first touch (the robot starts 0.5 mm above the floor) to the end or fall
        steps = np.arange(self.nstep)[None]
        airborne = ~down & (steps >= down.argmax(axis=1)[:, None]) & (steps <= last[:, None])
        flight_s = flight_steps(airborne, FLIGHT_MIN_STEPS) * self.dt
        if fitness_name(c.fitness) == "paper":
            credit = np.clip(forward, -c.forward_cap_m, c.forward_cap_m)
            fitness = t_fall + c.distance_weight * credit
        else:
            total = self.nstep * self.dt
            quality = forward - c.heading_weight * np.abs(heading) \
                - c.lateral_weight * np.abs(lateral) - c.flight_weight * flight_s \
                - c.excess_weight * (np.maximum(np.abs(heading) - c.heading_tolerance_rad, 0)
                                     + np.maximum(np.abs(lateral) - c.lateral_tolerance_m, 0)
                                     + flight_s) \
                + c.step_bonus_m * (forward >= c.step_min_m)
            fitness = np.where(fell, np.minimum(t_fall + 0.1 * np.clip(forward, -0.1, 0.1),
                                                total),
                               total + 1.0 + np.maximum(quality, -0.99))
        metrics = {
            "time_to_fall_s": t_fall, "forward_m": forward, "lateral_m": lateral,
            "heading_change_rad": heading, "flight_s": flight_s,
            "fell": fell.astype(float), "fall_rate": fell.astype(float),
            "stepped": ((forward >= c.step_min_m) & ~fell).astype(float),
        }
        return Evaluation(fitness, metrics)


    def _evaluate_batch(self, genomes: np.ndarray) -> Evaluation:
        genomes = np.atleast_2d(genomes)
        if self.worlds is None:
            return self.score(*self.simulate(genomes))
        return self.evaluate_worlds(genomes)

    def evaluate_worlds(self, genomes: np.ndarray) -> Evaluation:
        """Every genome in each of the K perturbed worlds (:mod:`evomotion.sim.worlds`),
        one batch; fitness = mean or ``world_quantile`` of the K values, metrics = means over
        the worlds, plus ``fall_rate``."""
        from evomotion.sim.worlds import aggregate_worlds, simulate_worlds

        worlds = self.worlds
        if worlds is None:
            raise ValueError("evaluate_worlds: the problem has one world (problem.worlds <= 1)")
        n, k = len(genomes), len(worlds)
        ctrl = np.repeat(self.controls(genomes), k, axis=0)  # genome-major: i * k + world
        states, sensors = simulate_worlds(worlds * n, self.state0, ctrl,
                                          self.sim.nthread, sensors=True, stopped=self._fallen,
                                          segment_steps=self.segment_steps,
                                          simulator=self.sim)
        # fall_rate: the share of worlds fallen
        return aggregate_worlds(self.score(states, sensors), n, k, self.cfg.world_aggregate,
                                self.cfg.world_quantile)
