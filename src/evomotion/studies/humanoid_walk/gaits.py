"""The two gaits the walk problem (:class:`~.problem.HumanoidWalkProblem`) can drive a robot
with, chosen by what the robot can do (:mod:`evomotion.sim.robots` capabilities):

- :class:`FootPlacementGait` (:mod:`.foot_gait`): feet placed in Cartesian space through a
  closed-form leg IK, key poses every 20 ms played as a ``.motion``, checked against the
  motors' no-load speeds: a robot with the capabilities ``leg_ik``, ``speed_limits`` and
  ``webots_names`` (the NAO);
- :class:`JointSpaceGait` (:mod:`.joint_gait`): phase-locked oscillators on the joint roles of
  the spec's ``[gait]``: any other robot (and a copy of ``nao.toml``, which has the NAO's
  description but not its code).

Each gives the genome, the rollout horizon, the initial states and servo targets of a batch,
and the per-genome facts the shared score needs (walk seconds, the speed ratio where motor
limits are known, the period where the straightness is measured).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evomotion.core.problem import GenomeSpec
from evomotion.errors import InputError
from evomotion.sim.motion import Motion
from evomotion.studies.humanoid_walk import foot_gait, joint_gait
from evomotion.studies.humanoid_walk.walk_motion import assemble_poses, parts_batch, whole_walk

BASE_METRICS = ("time_to_fall_s", "forward_m", "speed_mps", "lateral_m", "heading_change_rad",
                "heading_deg_per_m")
FOOT_CAPABILITIES = ("leg_ik", "speed_limits", "webots_names")


@dataclass
class GaitBatch:
    """A batch decoded for simulation: initial states (``[ns]`` shared or ``[P, ns]``),
    targets ``[P, nstep, nu]``, walk seconds ``[P]``; the speed ratio ``[P]`` (motor limits
    known) or ``None``; the period ``[P]`` (straightness measured) or ``None``."""

    init: np.ndarray
    ctrl: np.ndarray
    walk_s: np.ndarray
    speed_ratio: np.ndarray | None = None
    period_s: np.ndarray | None = None


class FootPlacementGait:
    """The 14-gene foot-placement walk of :mod:`.foot_gait` (see its module doc)."""

    name = "foot"
    metric_names: tuple[str, ...] = (*BASE_METRICS, "cost_of_transport", "fell", "fall_rate",
                                     "speed_ratio")

    def __init__(self, robot, cfg, dt: float) -> None:
        for cap in FOOT_CAPABILITIES:
            robot.capability(cap, "humanoid-walk-open-loop's foot-placement gait")
        limits = robot.capability("speed_limits", "humanoid-walk-open-loop").SPEED_LIMITS
        self.robot, self.cfg, self.dt = robot, cfg, dt
        self.kind = "biped"
        self.genome = GenomeSpec(foot_gait.LOWER.copy(), foot_gait.UPPER.copy(),
                                 names=foot_gait.NAMES)
        self.default = foot_gait.DEFAULT
        self.horizon_s = cfg.horizon_s()
        self.speed_limits = cfg.speed_margin * np.array([limits[j] for j in robot.joints])
        self.work_servos = None  # every actuator is a joint servo (the work of all of them)

    def motion(self, genes: np.ndarray) -> Motion:
        """The whole walk of one genome (:func:`.walk_motion.whole_walk`)."""
        return whole_walk(genes, self.cfg.walk_s)

    def batch(self, genomes: np.ndarray, nstep: int) -> GaitBatch:
        """Targets by :func:`~evomotion.sim.robots.nao.replay.motion_targets` of each genome's
        motion; the speed ratio is the fastest joint move between two key poses over
        ``speed_margin`` times that joint's motor limit (> 1: the real robot cannot play it)."""
        from evomotion.sim.robots.nao.replay import motion_targets

        joints = tuple(self.robot.joints)
        P = len(genomes)
        first = np.empty((P, len(joints)))
        ctrl = np.empty((P, nstep, len(joints)))
        walk = np.empty(P)
        ratio = np.empty(P)
        periods = foot_gait.period_ms(genomes[:, foot_gait.INDEX["period_s"]])
        for p in np.unique(periods):
            rows = np.flatnonzero(periods == p)
            s = foot_gait.schedule(p / 1000.0, self.cfg.walk_s, 0.0)
            start, cycle, stop = parts_batch(genomes[rows], s)
            q = assemble_poses(start, cycle, s.steady_ms // s.period_ms, stop)
            t = np.arange(q.shape[1], dtype=np.int64) * foot_gait.POSE_MS
            ratio[rows] = (np.abs(np.diff(q, axis=1)).max(axis=1)
                           / (foot_gait.POSE_MS / 1000.0) / self.speed_limits).max(axis=1)
            for r, qr in zip(rows, q, strict=True):
                first[r], ctrl[r] = motion_targets(Motion(joints, t, qr), self.dt, nstep)
            walk[rows] = (s.walk_end_ms - s.ready_ms) / 1000.0
        # every walk starts in the same crouch: one state per distinct first pose
        poses, inverse = np.unique(first, axis=0, return_inverse=True)
        states = np.stack([self.robot.state_at(f) for f in poses])
        return GaitBatch(states[np.asarray(inverse).ravel()], ctrl, walk, speed_ratio=ratio)


class JointSpaceGait:
    """The oscillator gait of :mod:`.joint_gait` on the robot's ``[gait]`` roles."""

    name = "joint"
    metric_names: tuple[str, ...] = (*BASE_METRICS, "straightness", "cost_of_transport", "fell",
                                     "fall_rate")

    def __init__(self, robot, cfg, dt: float) -> None:
        if robot.gait_kind is None:
            raise InputError(f"problem.robot: {robot.spec.path} has no [gait] section (the "
                             "channels of hip_pitch, knee, ankle_pitch, ...)")
        self.robot, self.cfg, self.dt = robot, cfg, dt
        self.kind = robot.gait_kind
        names, lo, hi, self.default = joint_gait.gene_table(self.kind)
        self.genome = GenomeSpec(lo, hi, names=names)
        self.horizon_s = float(joint_gait.walk_seconds(np.array([hi[0]]), cfg.walk_s)[0]
                               + cfg.hold_s)
        m = robot.model
        limited = m.actuator_ctrllimited.astype(bool)
        self.ctrl_lo = np.where(limited, m.actuator_ctrlrange[:, 0], -np.inf)
        self.ctrl_hi = np.where(limited, m.actuator_ctrlrange[:, 1], np.inf)
        #: the work of the joint servos only (actuators on tendons count none)
        self.work_servos = np.flatnonzero(m.actuator_trntype == 0)  # mjTRN_JOINT

    def targets(self, genomes: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Actuator targets ``[P, T, nu]`` at times ``t[T]`` (s)."""
        r = self.robot
        return joint_gait.targets(genomes, self.kind, r.gait, r.pose, self.ctrl_lo,
                                  self.ctrl_hi, t, self.cfg.walk_s)

    def motion(self, genes: np.ndarray) -> Motion:
        """The walk of one genome as a motion of the robot's channels, every 20 ms."""
        t_ms = np.arange(0, int(self.horizon_s * 1000) + 1, foot_gait.POSE_MS)
        q = self.targets(np.atleast_2d(genes), t_ms / 1000.0)[0]
        return Motion(tuple(self.robot.joints), t_ms, q)

    def batch(self, genomes: np.ndarray, nstep: int) -> GaitBatch:
        period = genomes[:, 0]
        ctrl = self.targets(genomes, self.dt * np.arange(nstep))
        return GaitBatch(self.robot.state0, ctrl,
                         joint_gait.walk_seconds(np.asarray(period, float), self.cfg.walk_s),
                         period_s=period)


def gait_for(robot, cfg, dt: float) -> FootPlacementGait | JointSpaceGait:
    """The foot-placement gait where the robot has its capabilities, else the joint-space
    gait of its ``[gait]`` section."""
    if all(robot.has(c) for c in FOOT_CAPABILITIES):
        return FootPlacementGait(robot, cfg, dt)
    return JointSpaceGait(robot, cfg, dt)

