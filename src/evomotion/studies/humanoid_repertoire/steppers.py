"""The two ways the repertoire problem (:class:`~.problem.HumanoidRepertoireProblem`) turns a
step's genes into a robot's servo targets, chosen by what the robot can do
(:mod:`evomotion.sim.robots` capabilities):

- :class:`ClosedFormStepper`: the key poses of :mod:`.step` through the closed-form leg IK
  (with the NAO's coupled hip yaw-pitch), played as Webots plays a ``.motion``
  (:func:`evomotion.sim.robots.nao.replay.motion_targets`): a robot with the capabilities
  ``leg_ik`` and ``webots_names`` (the NAO);
- :class:`NumericalStepper`: the same foot plan solved by the numerical leg IK of
  :mod:`.numerical_step`, scaled to the robot's size (:class:`.numerical_step.RobotStep`):
  any other biped, and a copy of ``nao.toml`` (the NAO's description without its code).

Each gives the genome bounds and default, the measure box, the horizon, the initial state,
the servos whose work counts, the metrics, and a batch's targets ``[P, nstep, nu]`` with the
physics step where each step's motion plus ``hold_s`` ends ``[P]`` and any extra metrics.
"""

from __future__ import annotations

import numpy as np

from evomotion.core.problem import MeasureSpec
from evomotion.sim.motion import Motion
from evomotion.sim.rollout import interpolate_controls
from evomotion.studies.humanoid_repertoire import step
from evomotion.studies.humanoid_repertoire.numerical_step import RobotStep

METRICS = ("time_to_fall_s", "fell", "dx_m", "dy_m", "dtheta_deg", "peak_tilt_deg", "work_j")
MEASURES = MeasureSpec(("dx_m", "dy_m", "dtheta_deg"), np.array([-0.10, -0.08, -45.0]),
                       np.array([0.15, 0.08, 45.0]), (10, 8, 9))
CLOSED_FORM_CAPABILITIES = ("leg_ik", "webots_names")


class ClosedFormStepper:
    """The NAO's step (:mod:`.step`): closed-form IK key poses every 20 ms."""

    name = "closed_form"
    metric_names: tuple[str, ...] = METRICS

    def __init__(self, robot, cfg, dt: float) -> None:
        for cap in CLOSED_FORM_CAPABILITIES:
            robot.capability(cap, "humanoid-repertoire's closed-form step")
        self.cfg, self.dt = cfg, dt
        self.lower, self.upper, self.default = step.LOWER.copy(), step.UPPER.copy(), step.DEFAULT
        self.measure_spec = MEASURES
        self.horizon_s = cfg.horizon_s()
        self.state0 = robot.state_at(step.ready_pose())
        self.work_servos = None  # every actuator is a joint servo
        self.nu = len(robot.joints)

    def motion(self, genes: np.ndarray) -> Motion:
        """The step of one genome as a Webots motion (ready pose to ready pose)."""
        from evomotion.studies.humanoid_repertoire.artifacts import step_motion

        return step_motion(genes)

    def controls(self, genomes: np.ndarray, nstep: int
                 ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        """Servo targets ``[P, nstep, nu]`` (each step's motion, then its last pose held),
        the last physics step of each step's motion plus ``hold_s`` ``[P]`` (the last step
        ``evomotion replay --hold hold_s`` simulates), no extra metrics."""
        from evomotion.sim.robots.nao.replay import motion_targets

        ctrl = np.empty((len(genomes), nstep, self.nu))
        end = np.empty(len(genomes), np.int64)
        for i, g in enumerate(genomes):
            m = self.motion(g)
            _, ctrl[i] = motion_targets(m, self.dt, nstep)
            end[i] = min(int(np.ceil((m.duration_s + self.cfg.hold_s) / self.dt)), nstep) - 1
        return ctrl, end, {}


class NumericalStepper(RobotStep):
    """Another biped's step: :class:`.numerical_step.RobotStep` key poses, linearly
    interpolated as a ``.motion`` is played; ``ik_error_m`` is the largest distance of a sole
    from its planned place (0 when the IK reached every key pose)."""

    name = "numerical"
    metric_names: tuple[str, ...] = (*METRICS, "ik_error_m")

    def __init__(self, robot, cfg, dt: float) -> None:
        super().__init__(robot)
        self.robot, self.cfg, self.dt = robot, cfg, dt
        self.measure_spec = self.measure_box(MEASURES)
        self.horizon_s = self.max_duration_s + cfg.hold_s
        self.state0 = robot.state0
        self.work_servos = np.flatnonzero(robot.model.actuator_trntype == 0)  # mjTRN_JOINT

    def motion(self, genes: np.ndarray) -> Motion:
        """The step of one genome as a motion of the robot's channels (ready pose to ready
        pose, every 20 ms)."""
        q = self.poses(np.asarray(genes, float)[None])[0][0]
        return Motion(self.robot.joints, np.arange(len(q), dtype=np.int64) * step.POSE_MS, q)

    def controls(self, genomes: np.ndarray, nstep: int
                 ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        keys, times, durations, ik_error = self.padded(genomes)
        ctrl = interpolate_controls(times, keys, self.dt, nstep)
        end = np.minimum(np.ceil((durations + self.cfg.hold_s) / self.dt).astype(np.int64),
                         nstep) - 1
        return ctrl, end, {"ik_error_m": ik_error}


def stepper_for(robot, cfg, dt: float) -> ClosedFormStepper | NumericalStepper:
    """The closed-form step where the robot has its capabilities, else the numerical one."""
    if all(robot.has(c) for c in CLOSED_FORM_CAPABILITIES):
        return ClosedFormStepper(robot, cfg, dt)
    return NumericalStepper(robot, cfg, dt)
