"""The forward-step problem of seed 000: evaluate a batch of leg trajectories on the NAO.

Each genome is decoded (see :mod:`.encoding`) into targets for the 10 leg servos on every
physics step of ``motion_s + hold_s`` seconds; the other 12 servos hold the initial pose.
The whole batch is rolled out with ``mujoco.rollout`` (threads = ``threads``) and scored from
the recorded torso states:

``fitness = time_to_fall_s + distance_weight * clip(forward_m, -forward_cap_m, forward_cap_m)``
(maximised; seconds, with ``distance_weight`` = 10 s/m and ``forward_cap_m`` = 0.2 m by default)

- ``time_to_fall_s``: time of the first fallen state (torso origin below ``fall_height_m`` or
  its up axis tilted more than ``fall_tilt_rad``), or the full ``motion_s + hold_s`` when the
  robot stays up (seed: "time from the start of the motion until the fall");
- ``forward_m``: displacement along +x (the robot's initial heading) of the midpoint of the
  two sole centres, at the end or at the moment of the fall. Measuring the feet, not the
  torso, means that leaning or diving forward earns nothing: only moving the feet does.
The cap keeps a lunge or a dive (feet thrown 0.5 m forward, then a fall) from beating a robot
that stays up: distance credit is at most 2 s, less than a full ``motion_s + hold_s``.
A *step* is ``forward_m >= step_min_m`` (5 cm) without falling (so upright at the end: the
last knot is the initial pose, held for ``hold_s``).

Rollouts run in segments of ``segment_s``; robots that have fallen are not simulated further
(their remaining states repeat the fallen state), which saves most of the physics early in a
run when nearly every individual falls.
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
from evomotion.sim.nao.scene import sensor_slices
from evomotion.sim.rollout import BatchSimulator, fall_step, torso_track
from evomotion.studies.humanoid_step.encoding import ENCODINGS, ServoEncoding

#: Seed 000, Table 1: servo angle limits (rad) used as GA bounds.
SEED_TABLE1: dict[str, tuple[float, float]] = {
    "LKneePitch": (0.0, 2.2689), "RKneePitch": (0.0, 2.2689),
    "LAnkleRoll": (-0.7854, 0.4363), "RAnkleRoll": (-0.4363, 0.7854),
    "LHipRoll": (-0.4363, 0.7854), "RHipRoll": (-0.7854, 0.4363),
    "LAnklePitch": (-1.309, 0.7854), "RAnklePitch": (-1.309, 0.7854),
    "LHipPitch": (-1.7453, 0.4363), "RHipPitch": (-1.7453, 0.4363),
}
METRICS = ("time_to_fall_s", "forward_m", "lateral_m", "heading_change_rad", "fell", "stepped")


#: ``problem.intervals`` at most; ``problem.threads`` at most (one MjData per thread)
MAX_INTERVALS = 10_000
MAX_THREADS = 1024
#: the NAO model's physics step (``models/nao_h25.xml``), for estimates before it is loaded
NAO_TIMESTEP_S = 0.004
#: doubles recorded per individual and physics step: state (58), sensors, controls (22),
#: leg targets, rounded up
ROLLOUT_DOUBLES_PER_STEP = 100


@dataclass(frozen=True)
class HumanoidStepConfig:
    """The ``[problem]`` section of ``humanoid-step``."""

    encoding: str = "linear"  # linear | spline | harmonic
    intervals: int = 20  # K time intervals of the step (seed: 20)
    motion_s: float = 2.0  # duration of the step motion T (s)
    hold_s: float = 1.0  # initial pose held after the motion (s)
    distance_weight: float = 10.0  # fitness per metre forward (s/m)
    forward_cap_m: float = 0.2  # forward distance credited at most (m)
    fall_height_m: float = nao.FALL_HEIGHT_M
    fall_tilt_rad: float = nao.FALL_TILT_RAD  # 45 degrees
    step_min_m: float = 0.05
    bounds_scale: float = 1.0  # 1 = seed Table 1 (intersected with the model ranges)
    threads: int = 0  # mujoco.rollout threads; 0 = all cores
    segment_s: float = 0.2  # fallen robots stop being simulated at these boundaries (s)

    def for_worker(self) -> HumanoidStepConfig:
        """The config of a one-core evaluator worker: ``threads`` 0 (all cores) becomes 1;
        an explicit thread count is kept."""
        return dataclasses.replace(self, threads=1) if self.threads == 0 else self

    def validate(self) -> None:
        """One-line :class:`InputError` for impossible settings (see :func:`validate`)."""
        validate(self)

    def genome_dim(self) -> int:
        """The genome's length (for the memory check before the problem is built)."""
        n = len(nao.LEG_SERVOS)
        return 3 * n + 1 if self.encoding == "harmonic" else n * (self.intervals - 1)

    memory_keys = ("motion_s", "hold_s")  # what memory_bytes depends on (for its message)

    def memory_bytes(self, pop_size: int) -> int:
        """Bytes of one batch's rollout: recorded states, sensors and controls (doubles) of
        every physics step of the motion and the hold, twice (analysis temporaries)."""
        steps = math.ceil((self.motion_s + self.hold_s) / NAO_TIMESTEP_S)
        return 2 * 8 * pop_size * steps * ROLLOUT_DOUBLES_PER_STEP


def servo_bounds(model, scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Seed Table 1 intersected with the model's joint ranges for ``nao.LEG_SERVOS``; with
    ``scale < 1`` each interval shrinks towards the initial pose by that factor."""
    rng = nao.joint_ranges(model, nao.LEG_SERVOS)
    t1 = np.array([SEED_TABLE1[n] for n in nao.LEG_SERVOS])
    lo, hi = np.maximum(rng[:, 0], t1[:, 0]), np.minimum(rng[:, 1], t1[:, 1])
    q0 = leg_initial_pose()
    return q0 + scale * (lo - q0), q0 + scale * (hi - q0)


def leg_initial_pose() -> np.ndarray:
    return nao.pose_vector()[nao.joint_columns(nao.LEG_SERVOS)]


def validate(cfg: HumanoidStepConfig) -> None:
    """One-line :class:`InputError` for impossible settings."""
    check_fields(cfg, "problem")
    check_choice("problem.encoding", cfg.encoding, ENCODINGS)
    check_number("problem.intervals", cfg.intervals, lo=2, hi=MAX_INTERVALS, integer=True)
    check_number("problem.threads", cfg.threads, lo=0, hi=MAX_THREADS, integer=True)
    check_number("problem.fall_height_m", cfg.fall_height_m, lo=0.0, lo_open=True)
    check_number("problem.fall_tilt_rad", cfg.fall_tilt_rad, lo=0.0, hi=math.pi, lo_open=True)
    check_number("problem.step_min_m", cfg.step_min_m, lo=0.0)
    checks = [(cfg.intervals >= 2, "problem.intervals must be >= 2"),
              (cfg.motion_s > 0, "problem.motion_s must be > 0"),
              (cfg.hold_s >= 0, "problem.hold_s must be >= 0"),
              (0 < cfg.bounds_scale <= 1, "problem.bounds_scale must be in (0, 1]"),
              (cfg.segment_s > 0, "problem.segment_s must be > 0"),
              (cfg.threads >= 0, "problem.threads must be >= 0 (0 = all cores)"),
              (cfg.forward_cap_m > 0, "problem.forward_cap_m must be > 0")]
    for ok, message in checks:
        if not ok:
            raise InputError(message)


class HumanoidStepProblem:
    """Batch evaluation of forward-step trajectories (fitness maximised)."""

    sense = "max"
    metric_names = METRICS

    def __init__(self, cfg: HumanoidStepConfig | None = None) -> None:
        self.cfg = cfg = cfg or HumanoidStepConfig()
        validate(cfg)
        self.model = nao.load_model()
        self.dt = float(self.model.opt.timestep)
        lo, hi = servo_bounds(self.model, cfg.bounds_scale)
        self.encoding = ServoEncoding(cfg.encoding, leg_initial_pose(), lo, hi, cfg.intervals,
                                      cfg.motion_s)
        self.genome: GenomeSpec = self.encoding.genome(nao.LEG_SERVOS)
        self.nstep = int(round((cfg.motion_s + cfg.hold_s) / self.dt))
        self.t_step = self.dt * np.arange(self.nstep)  # target applied during step i
        self.leg_columns = np.array(nao.joint_columns(nao.LEG_SERVOS))
        self.base = nao.pose_vector()
        self.state0 = nao.initial_state(self.model)
        data0 = nao.initial_data(self.model)
        self.sole0 = 0.5 * (data0.site("l_sole_site").xpos + data0.site("r_sole_site").xpos)
        self.sole_columns = [sensor_slices(self.model)[s] for s in ("l_sole", "r_sole")]
        self.segment_steps = max(1, int(round(cfg.segment_s / self.dt)))
        self.sim = BatchSimulator(self.model, cfg.threads)

    def controls(self, genomes: np.ndarray, t: np.ndarray | None = None) -> np.ndarray:
        """Actuator targets ``[pop, nstep, 22]`` for a batch of genomes."""
        t = self.t_step if t is None else t
        legs = self.encoding.targets(genomes, t)
        ctrl = np.broadcast_to(self.base, (legs.shape[0], legs.shape[1], self.base.size)).copy()
        ctrl[:, :, self.leg_columns] = legs
        return ctrl

    def _fallen(self, states: np.ndarray) -> np.ndarray:
        c = self.cfg
        return fall_step(torso_track(states), c.fall_height_m,
                         c.fall_tilt_rad) < states.shape[1]

    def simulate(self, genomes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Recorded (states, sole positions) of a batch, fallen robots stopped early."""
        return self.sim.run_until(self.state0, self.controls(genomes), self._fallen,
                                  self.segment_steps)

    def score(self, states: np.ndarray, sensors: np.ndarray) -> Evaluation:
        """Fitness and metrics from recorded states ``[pop, nstep, nstate]`` and sensors."""
        c = self.cfg
        track = torso_track(states)
        fall = fall_step(track, c.fall_height_m, c.fall_tilt_rad)
        fell = fall < self.nstep
        last = np.minimum(fall, self.nstep - 1)
        rows = np.arange(states.shape[0])
        soles = sensors[rows, last]
        left, right = (soles[:, cols][:, :2] for cols in self.sole_columns)
        end = 0.5 * (left + right)
        t_fall = np.where(fell, (fall + 1) * self.dt, self.nstep * self.dt)
        forward, lateral = end[:, 0] - self.sole0[0], end[:, 1] - self.sole0[1]
        credit = np.clip(forward, -c.forward_cap_m, c.forward_cap_m)
        fitness = t_fall + c.distance_weight * credit
        metrics = {
            "time_to_fall_s": t_fall, "forward_m": forward, "lateral_m": lateral,
            "heading_change_rad": track.yaw_rad[rows, last] - track.yaw_rad[:, 0],
            "fell": fell.astype(float),
            "stepped": ((forward >= c.step_min_m) & ~fell).astype(float),
        }
        return Evaluation(fitness, metrics)

    def evaluate(self, genomes: np.ndarray) -> Evaluation:
        return self.score(*self.simulate(np.atleast_2d(genomes)))
