"""The two ways the kick problem (:class:`.problem.KickProblem`) turns a kick's genes into a
robot's servo targets in its scene, chosen by what the robot can do
(:mod:`evomotion.sim.robots` capabilities):

- :class:`ClosedFormKick`: the NAO's kick (:mod:`.motion`: closed-form leg IK with its coupled
  hip yaw-pitch, the NAO's joint ranges and motor speeds as constraints) in the NAO's kick
  scene (:mod:`.scene`): a robot with the capabilities ``leg_ik``, ``speed_limits`` and
  ``webots_names`` (the NAO);
- :class:`.robot_motion.NumericalKick`: the same kick scaled to the robot and solved by the
  numerical leg IK, in the scene of :mod:`.robot_scene`: any other biped (the OP3), and a
  copy of ``nao.toml`` (the NAO's description without its code).

Each gives the genome bounds and start, the scene (model, MJCF text for videos, initial
state, sole rectangle, the right toe, the ball's rolling deceleration, the ball's gap in
front of the toe), the feet's paths, a batch's joint targets with its IK error (``None``:
exact), the joint limits (``None``: the NAO's), the fall thresholds and one kick as a
motion.
"""

from __future__ import annotations

import numpy as np

from evomotion.sim.motion import Motion
from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.joint_limits import JOINT_RANGES
from evomotion.sim.robots.nao.mirror import mirror_targets
from evomotion.studies.biped_kick import scene
from evomotion.studies.biped_kick.motion import (
    BALL_GAP_M,
    GENES,
    START,
    foot_trajectories,
    joint_targets,
    kick_motion,
)
from evomotion.studies.biped_kick.robot_motion import NumericalKick

CLOSED_FORM_CAPABILITIES = ("leg_ik", "speed_limits", "webots_names")


class ClosedFormKick:
    """The NAO's kick (:mod:`.motion`) in the NAO's kick scene (:mod:`.scene`)."""

    name = "closed_form"
    limits = None  # limit_excess' default: the NAO's ranges and motor speeds
    gap_m = BALL_GAP_M
    sole_half = scene.SOLE_HALF_M
    #: targets in mirror image: the left-foot kick (the NAO is symmetric)
    mirror = staticmethod(mirror_targets)
    #: the kicking (right) ankle's roll: its column and the range a foot in the air may be
    #: rolled into (:func:`.adaptive.rolled_in_air`): its own range and the left ankle's in
    #: mirror image, so that the mirrored left-foot kick stays within its range too
    swing_roll = (nao.JOINTS.index("RAnkleRoll"),
                  max(JOINT_RANGES["RAnkleRoll"][0], -JOINT_RANGES["LAnkleRoll"][1]),
                  min(JOINT_RANGES["RAnkleRoll"][1], -JOINT_RANGES["LAnkleRoll"][0]))

    def __init__(self, robot, cfg) -> None:
        for cap in CLOSED_FORM_CAPABILITIES:
            robot.capability(cap, "biped-kick's closed-form kick")
        self.robot = robot
        self.lower = np.array([g[1] for g in GENES])
        self.upper = np.array([g[2] for g in GENES])
        self.start = np.array([START[g[0]] for g in GENES])
        self.model = scene.load_scene(cfg.rolling_m)
        self.scene_xml = scene.kick_scene_xml(rolling_m=cfg.rolling_m)
        self.decel = scene.measured_deceleration(cfg.rolling_m)
        self.toe = scene.default_ball_xy(self.model, gap_m=0.0) - [scene.BALL_RADIUS_M, 0.0]
        self.fall_height_m, self.fall_tilt_rad = cfg.fall_height_m, cfg.fall_tilt_rad

    def initial_state(self, ball_xy: np.ndarray, pose: np.ndarray | None = None
                      ) -> np.ndarray:
        return scene.initial_scene_state(self.model, ball_xy, pose)

    def foot_trajectories(self, genomes: np.ndarray, times_s: np.ndarray,
                          aims_rad: np.ndarray | float = 0.0) -> dict[str, np.ndarray]:
        return foot_trajectories(genomes, times_s, aims_rad)

    def joint_targets(self, genomes: np.ndarray, times_s: np.ndarray,
                      aims_rad: np.ndarray | float = 0.0,
                      ball_shift: np.ndarray | None = None) -> tuple[np.ndarray, None]:
        return joint_targets(genomes, times_s, aims_rad, ball_shift), None

    def kick_motion(self, genome: np.ndarray, aim_rad: float = 0.0) -> Motion:
        return kick_motion(genome, aim_rad)


def kicker_for(robot, cfg) -> ClosedFormKick | NumericalKick:
    """The closed-form kick where the robot has its capabilities, else the numerical one."""
    if all(robot.has(c) for c in CLOSED_FORM_CAPABILITIES):
        return ClosedFormKick(robot, cfg)
    return NumericalKick(robot, cfg.rolling_m)
