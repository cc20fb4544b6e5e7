"""The repertoire problem: one step of a robot (:mod:`.step`), described by what it does; the
robot (``problem.robot``, the NAO by default) is a parameter.

Each genome's key poses (every 20 ms, ready pose to ready pose; the NAO's through its
closed-form leg IK, another biped's through a numerical one, :mod:`.steppers`) become one
servo target per physics step by the linear interpolation a ``.motion`` is played with
(:func:`evomotion.sim.robots.nao.replay.motion_targets` on the NAO), from the robot standing
in the ready pose, on the model every study uses; the motion is followed by ``hold_s`` (2 s)
in the ready pose. So the cell's exported ``.motion`` replayed with ``evomotion replay
--hold 2`` is the evaluated rollout (measured at the same physics step; the batch runs to
the longest step's end).

Measures (behaviour descriptors), at the end of the hold, in the robot's initial frame:
``dx_m`` / ``dy_m``, the torso's displacement (forward / left; the torso stands over the
middle of the feet in the ready pose before and after, so this is the feet's displacement
too), and ``dtheta_deg``, its yaw change.

Objective (maximised), stability minus effort: a robot that stays up scores
``-peak_tilt_rad - effort_weight * work_J`` (the largest tilt of the torso's up axis from
vertical during the step and the hold; the servos' mechanical work, :class:`~evomotion.sim.
rollout.ServoWork`; 0.01 per J): between about -1 and 0; one that falls scores
``-10 + time_up_s / horizon_s``, below every standing one. QD-scores use the offset -10.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from evomotion.core.checks import check_fields, check_number, check_text
from evomotion.core.problem import Evaluation, GenomeSpec, Sense
from evomotion.errors import InputError
from evomotion.sim.backend import BatchedRollouts, make_simulator
from evomotion.sim.motion import Motion
from evomotion.sim.physics_config import PhysicsConfig, validate_physics
from evomotion.sim.robots import nao
from evomotion.sim.rollout import ServoWork, fall_step, fell, torso_track
from evomotion.studies.humanoid_repertoire import step
from evomotion.studies.humanoid_repertoire.steppers import MEASURES, METRICS, stepper_for

FALLEN_OBJECTIVE = -10.0
NAO_TIMESTEP_S = 0.004
#: the documented ranges of the ``[problem]`` floats: hold (s), objective lost per joule,
#: fall height (m; no biped's torso falls from higher)
MAX_HOLD_S = 60.0
MAX_EFFORT_WEIGHT = 100.0
MAX_FALL_HEIGHT_M = 5.0


@dataclass(frozen=True)
class RepertoireKeys:
    """The repertoire's own keys of ``[problem]`` (first in ``config.toml``; the physics keys
    are :mod:`evomotion.sim.physics_config`'s)."""

    hold_s: float = 2.0  # the ready pose held after the step (s)
    effort_weight: float = 0.01  # objective lost per joule of servo work
    fall_height_m: float = nao.FALL_HEIGHT_M
    fall_tilt_rad: float = nao.FALL_TILT_RAD


@dataclass(frozen=True)
class HumanoidRepertoireConfig(PhysicsConfig, RepertoireKeys):
    """The ``[problem]`` section of ``humanoid-repertoire``: its own keys
    (:class:`RepertoireKeys`), the physics' (:mod:`evomotion.sim.physics_config`), the
    robot."""

    #: the robot: "" or "nao" (the NAO, through its closed-form leg IK), another bundled
    #: biped (op3, dm-humanoid) or a spec .toml (sim/robots): the same step, scaled to its
    #: size, through a numerical leg IK (numerical_step.py); its [fall] thresholds apply
    #: unless fall_height_m / fall_tilt_rad are set
    robot: str = ""

    def validate(self) -> None:
        check_fields(self, "problem")
        check_number("problem.hold_s", self.hold_s, lo=0.0, hi=MAX_HOLD_S)
        check_number("problem.effort_weight", self.effort_weight, lo=0.0,
                     hi=MAX_EFFORT_WEIGHT)
        check_number("problem.fall_height_m", self.fall_height_m, lo=0.0,
                     hi=MAX_FALL_HEIGHT_M, lo_open=True)
        check_number("problem.fall_tilt_rad", self.fall_tilt_rad, lo=0.0, hi=math.pi,
                     lo_open=True)
        validate_physics(self)
        check_text("problem.robot", self.robot)

    def genome_dim(self) -> int:
        return len(step.GENES)

    def horizon_s(self) -> float:
        return step.MAX_DURATION_S + self.hold_s

    memory_keys = ("hold_s", "batch_rollouts")

    def memory_bytes(self, pop_size: int) -> int:
        """Recorded states of one batch of at most ``batch_rollouts`` rollouts (about 90
        doubles per physics step), twice."""
        rollouts = min(pop_size, self.batch_rollouts)
        return 2 * 8 * rollouts * math.ceil(self.horizon_s() / NAO_TIMESTEP_S) * 90


class HumanoidRepertoireProblem(BatchedRollouts):
    """Batch evaluation of steps of one robot (``cfg.robot``, the NAO by default; a biped with
    feet ``left`` and ``right``): objective and (dx, dy, dtheta) measures. The key poses
    come from the stepper its capabilities allow (:func:`.steppers.stepper_for`)."""

    sense: Sense = "max"
    metric_names: tuple[str, ...] = METRICS  # the instance's: its stepper's
    measure_spec = MEASURES  # the instance's: scaled to the robot's size

    def __init__(self, cfg: HumanoidRepertoireConfig | None = None) -> None:
        from evomotion.sim.robots import load_robot

        self.cfg = cfg = cfg or HumanoidRepertoireConfig()
        cfg.validate()
        r = self.robot = load_robot(cfg.robot or "nao")
        if set(r.feet) != {"left", "right"}:
            raise InputError(f"problem.robot: {r.name} has feet {', '.join(r.feet)}; a step "
                             "needs a biped with feet 'left' and 'right'")
        self.model = m = r.model
        self.dt = float(m.opt.timestep)
        self.steps = stepper_for(r, cfg, self.dt)
        self.metric_names = self.steps.metric_names
        self.genome = GenomeSpec(self.steps.lower, self.steps.upper, names=step.NAMES)
        self.measure_spec = self.steps.measure_spec
        self.horizon_s = self.steps.horizon_s
        self.nstep = int(math.ceil(self.horizon_s / self.dt))
        self.sim = make_simulator(m, cfg, cfg.threads)
        self.segment_steps = max(1, int(round(cfg.segment_s / self.dt)))
        self.state0 = self.steps.state0
        self.work = ServoWork(m, self.steps.work_servos)
        self.fall_height_m, self.fall_tilt_rad = r.fall_thresholds(cfg.fall_height_m,
                                                                   cfg.fall_tilt_rad)

    def initial_population(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """The in-place step (the stepper's default; CMA-ME's emitters start from it)."""
        return np.tile(self.steps.default, (max(int(n), 1), 1))

    def motion(self, genes: np.ndarray) -> Motion:
        """The step of one genome as a motion of the robot's joints (ready pose to ready
        pose)."""
        return self.steps.motion(genes)

    def controls(self, genomes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Servo targets ``[P, nstep, nu]`` (each step's motion, then its last pose held) and
        the last physics step of each step's motion plus ``hold_s`` ``[P]``, where it is
        measured: the last step ``evomotion replay --hold hold_s`` simulates."""
        return self.steps.controls(genomes, self.nstep)[:2]

    def _fallen(self, states: np.ndarray) -> np.ndarray:
        return fell(states, self.fall_height_m, self.fall_tilt_rad)

    def _evaluate_batch(self, genomes: np.ndarray) -> Evaluation:
        genomes = np.atleast_2d(np.asarray(genomes, dtype=float))
        ctrl, end, extra = self.steps.controls(genomes, self.nstep)
        states, _ = self.sim.run_until(self.state0, ctrl, self._fallen, self.segment_steps)
        ev = self.score(states, ctrl, end)
        ev.metrics.update(extra)
        return ev

    def score(self, states: np.ndarray, ctrl: np.ndarray, end: np.ndarray) -> Evaluation:
        """Objective, metrics and measures from recorded ``states[P, nstep, ns]``, measured
        at step ``end[P]`` (or at the fall, when it comes first)."""
        c = self.cfg
        track = torso_track(states)
        fall = fall_step(track, self.fall_height_m, self.fall_tilt_rad)
        fell_ = fall <= end
        last = np.minimum(fall, end)
        rows = np.arange(len(states))
        yaw0 = track.yaw_rad[:, 0]
        d = track.xyz[rows, last, :2] - track.xyz[:, 0, :2]
        cy, sy = np.cos(yaw0), np.sin(yaw0)
        dx, dy = cy * d[:, 0] + sy * d[:, 1], -sy * d[:, 0] + cy * d[:, 1]
        dtheta = np.degrees(track.yaw_rad[rows, last] - yaw0)
        tilt = np.arccos(np.clip(track.up_z, -1.0, 1.0))
        alive = np.arange(self.nstep)[None] <= last[:, None]
        peak = np.where(alive, tilt, 0.0).max(axis=1)
        work = self.work(states, ctrl, last)
        t_up = np.where(fell_, fall + 1, end + 1) * self.dt
        objective = np.where(fell_, FALLEN_OBJECTIVE + t_up / self.horizon_s,
                             -peak - c.effort_weight * work)
        metrics = {"time_to_fall_s": t_up, "fell": fell_.astype(float), "dx_m": dx,
                   "dy_m": dy, "dtheta_deg": dtheta, "peak_tilt_deg": np.degrees(peak),
                   "work_j": work}
        return Evaluation(objective, metrics, measures=np.stack([dx, dy, dtheta], axis=1))


def make_problem(cfg: HumanoidRepertoireConfig) -> HumanoidRepertoireProblem:
    """The repertoire of ``cfg.robot`` (the NAO by default)."""
    if not isinstance(cfg, HumanoidRepertoireConfig):
        raise InputError("humanoid-repertoire: expected a HumanoidRepertoireConfig")
    return HumanoidRepertoireProblem(cfg)
