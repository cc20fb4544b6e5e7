"""The repertoire problem on another biped (``problem.robot``): the step of
:mod:`.robot_step` on a robot of :mod:`evomotion.sim.robot`, scored like the NAO's
(:class:`~.problem.HumanoidRepertoireProblem`: the same objective, metrics and measures,
the measure box scaled to the robot's size).

Each genome's key poses (every 20 ms, ready pose to ready pose, the robot's spec pose) become
one target per physics step by linear interpolation, as a ``.motion`` is played
(:func:`evomotion.sim.robot.play.play_motion`), from the robot's initial state; the step is
followed by ``hold_s`` in the ready pose. ``ik_error_m`` is the largest distance of a sole
from its planned place in the step's key poses (0 when the IK reached every one; a step
beyond the robot's joint ranges is played as near as they allow).
"""

from __future__ import annotations

import math

import numpy as np

from evomotion.core.problem import Evaluation, GenomeSpec
from evomotion.errors import InputError
from evomotion.sim.backend import make_simulator
from evomotion.sim.nao.motion import Motion
from evomotion.sim.rollout import ServoWork, interpolate_controls
from evomotion.studies.humanoid_repertoire import step
from evomotion.studies.humanoid_repertoire.problem import (
    MEASURES,
    METRICS,
    HumanoidRepertoireConfig,
    HumanoidRepertoireProblem,
)
from evomotion.studies.humanoid_repertoire.robot_step import RobotStep


class RobotRepertoireProblem(HumanoidRepertoireProblem):
    """Batch evaluation of a robot's steps: objective and (dx, dy, dtheta) measures."""

    metric_names = (*METRICS, "ik_error_m")

    def __init__(self, cfg: HumanoidRepertoireConfig) -> None:
        from evomotion.sim.robot import load_robot

        self.cfg = cfg
        cfg.validate()
        r = self.robot = load_robot(cfg.robot or "nao")
        self.is_nao = False
        if set(r.feet) != {"left", "right"}:
            raise InputError(f"problem.robot: {r.name} has feet {', '.join(r.feet)}; a step "
                             "needs a biped with feet 'left' and 'right'")
        self.steps = RobotStep(r)
        self.model = m = r.model
        self.dt = float(m.opt.timestep)
        self.genome = GenomeSpec(self.steps.lower, self.steps.upper, names=step.NAMES)
        self.measure_spec = self.steps.measure_spec(MEASURES)
        self.horizon_s = self.steps.max_duration_s + cfg.hold_s
        self.nstep = int(math.ceil(self.horizon_s / self.dt))
        self.sim = make_simulator(m, cfg, cfg.threads)
        self.segment_steps = max(1, int(round(cfg.segment_s / self.dt)))
        self.state0 = r.state0
        joint_servos = np.flatnonzero(m.actuator_trntype == 0)  # mjTRN_JOINT
        self.work = ServoWork(m, joint_servos)
        self.fall_height_m, self.fall_tilt_rad = r.fall_thresholds(cfg.fall_height_m,
                                                                   cfg.fall_tilt_rad)

    def initial_population(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """The in-place step (scaled :data:`.step.DEFAULT`)."""
        return np.tile(self.steps.default, (max(int(n), 1), 1))

    def motion(self, genes: np.ndarray) -> Motion:
        """The step of one genome as a motion of the robot's channels (ready pose to ready
        pose, every 20 ms)."""
        q = self.steps.poses(np.asarray(genes, float)[None])[0][0]
        return Motion(self.robot.joints, np.arange(len(q), dtype=np.int64) * step.POSE_MS, q)

    def controls(self, genomes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Servo targets ``[P, nstep, nu]`` and the step where each step's motion plus
        ``hold_s`` ends ``[P]`` (see :meth:`HumanoidRepertoireProblem.controls`)."""
        return self._controls(genomes)[:2]

    def _controls(self, genomes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        keys, times, durations, ik_error = self.steps.padded(genomes)
        ctrl = interpolate_controls(times, keys, self.dt, self.nstep)
        end = np.minimum(np.ceil((durations + self.cfg.hold_s) / self.dt).astype(np.int64),
                         self.nstep) - 1
        return ctrl, end, ik_error

    def _evaluate_batch(self, genomes: np.ndarray) -> Evaluation:
        genomes = np.atleast_2d(np.asarray(genomes, dtype=float))
        ctrl, end, ik_error = self._controls(genomes)
        states, _ = self.sim.run_until(self.state0, ctrl, self._fallen, self.segment_steps)
        ev = self.score(states, ctrl, end)
        ev.metrics["ik_error_m"] = ik_error
        return ev
