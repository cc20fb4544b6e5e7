"""The kick of :mod:`.motion` on any biped: the same genes and foot paths, scaled to the robot,
solved by the numerical leg IK of :mod:`evomotion.sim.leg_ik`, in the scene of
:mod:`.robot_scene`.

The feet start where the robot's ready pose (its spec's initial pose) puts its soles, and
every 20 ms key pose of :func:`.motion.foot_trajectories` is solved for both legs at once
(torso upright; the stance foot flat; the kicking foot pitched and turned by its pitch and
yaw about the vertical and its own y axis). Each leg is solved on its own: the NAO's coupled
hip yaw-pitch (and the torso yaw that reconciles it, :func:`.motion.leg_joints`) does not
exist here. The IK keeps every joint in its range, so the range constraint never binds;
motor speeds are a constraint only for a robot with the ``speed_limits`` capability.

Size, as :mod:`evomotion.studies.humanoid_repertoire.numerical_step` scales the step (the
genes keep the NAO's names and meanings): the swing lengths (``lift_*``, ``kick_*``,
``*_bulge_m``, ``kick_y_m``) scale with ``s`` = the robot's hip-to-sole height over the
NAO's in its kick crouch (:data:`NAO_HIP_TO_SOLE_M`), durations with ``sqrt(s)`` (Froude
similarity), ``shift_y_m`` with the half distance of the feet over the NAO's; the ball's
place with the sole (read from the model, :func:`.robot_scene.sole_half`): its gap in front
of the toe (:data:`.motion.BALL_GAP_M`) with the sole's length over the NAO's
(:data:`evomotion.sim.robots.nao.SOLE_HALF_M`), its lateral place (``contact_y_m``,
``aim_contact_m_per_rad``) with the sole's width. Angles and ``kick_ease`` do not scale.

One difference from the NAO's kick: the retract (kick point back to rest) is bulged upward by
:data:`SET_DOWN_BULGE_M` x ``s`` (the NAO's is straight), so the foot comes down onto its place
from above. A robot with softer servos than the NAO's (the OP3: 4.1 N m, kp 24) sags a few
millimetres on its stance leg; a straight retract then touched down early, the foot was
dragged back on the floor, landed 3 cm forward and 1.3 cm inward, and the robot fell during the
shift back in 23 of 24 variants of the start (measured on the OP3, December 2026; with the
bulge 2 of 8).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from evomotion.sim.leg_ik import LegChain, torso_frame_feet
from evomotion.sim.motion import Motion
from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.leg_ik import rot_y, rot_z
from evomotion.studies.biped_kick import robot_scene
from evomotion.studies.biped_kick.motion import (
    BALL_GAP_M,
    GENE_INDEX,
    GENES,
    START,
    foot_trajectories,
    key_times,
    rest_pose,
)
from evomotion.studies.biped_kick.scene import rolling_slope

_, _NAO_L0, _NAO_R0 = rest_pose()
#: the NAO's kick crouch: hip (its pitch/roll axes) to sole, vertical [m]
NAO_HIP_TO_SOLE_M = -nao.HIP_OFFSET_Z_M - (_NAO_L0[2] - nao.FOOT_HEIGHT_M)
#: the NAO's kick crouch: half the distance between its ankles [m]
NAO_HALF_WIDTH_M = 0.5 * (_NAO_L0[1] - _NAO_R0[1])
LENGTH_GENES = ("lift_x_m", "lift_z_m", "lift_bulge_m", "kick_x_m", "kick_z_m",
                "kick_bulge_m", "kick_y_m")
TIME_GENES = ("t_shift_s", "t_lift_s", "t_kick_s", "t_retract_s")
BALL_GENES = ("contact_y_m", "aim_contact_m_per_rad")
#: the retract's upward bulge for a robot of the NAO's size [m] (scaled by ``s``)
SET_DOWN_BULGE_M = 0.03


class NumericalKick:
    """The kick of any biped with feet ``left`` and ``right`` (a
    :class:`~evomotion.sim.robots.Robot`): scaled genes, scene, joint targets and limits."""

    name = "numerical"

    mirror = None  # no left-foot kick: the robot's symmetry is not known
    #: no foot roll in the air (:func:`.adaptive.rolled_in_air`): the numerical IK keeps every
    #: joint within its range and reports how far it missed the foot's place instead
    swing_roll = None

    def __init__(self, robot, rolling_m: float) -> None:
        self.robot = robot
        self.legs = {f: LegChain(robot, f, robot.pose) for f in ("left", "right")}
        feet = torso_frame_feet(robot, robot.pose)
        self.rest = (feet["left"][0], feet["right"][0])
        self.rest_rot = (feet["left"][1], feet["right"][1])
        self.scale = float(np.mean([leg.hip_to_sole() for leg in self.legs.values()])
                           / NAO_HIP_TO_SOLE_M)
        self.sole_half = robot_scene.sole_half(robot, "right")
        factor = np.ones(len(GENES))
        for names, f in ((LENGTH_GENES, self.scale), (TIME_GENES, math.sqrt(self.scale)),
                         (("shift_y_m",), 0.5 * abs(self.rest[0][1] - self.rest[1][1])
                          / NAO_HALF_WIDTH_M),
                         (BALL_GENES, self.sole_half[1] / nao.SOLE_HALF_M[1])):
            for n in names:
                factor[GENE_INDEX[n]] = f
        self.factor = factor
        self.lower = np.array([g[1] for g in GENES]) * factor
        self.upper = np.array([g[2] for g in GENES]) * factor
        self.start = np.array([START[g[0]] for g in GENES]) * factor
        self.gap_m = BALL_GAP_M * self.sole_half[0] / nao.SOLE_HALF_M[0]
        self.retract_bulge_m = SET_DOWN_BULGE_M * self.scale
        spec = robot_scene.scene_spec(robot, rolling_m)
        self.model = spec.compile()
        self.scene_xml = spec.to_xml()
        m = robot.model
        limited = m.actuator_ctrllimited.astype(bool)
        vmax = np.full(m.nu, np.inf)
        if robot.has("speed_limits"):
            speeds = robot.capability("speed_limits", "the kick").SPEED_LIMITS
            vmax = np.array([speeds.get(j, np.inf) for j in robot.joints])
        self.limits = (np.where(limited, m.actuator_ctrlrange[:, 0], -np.inf),
                       np.where(limited, m.actuator_ctrlrange[:, 1], np.inf), vmax)
        self.toe = self._toe()
        self.decel = rolling_slope(self.model, self.initial_state(np.array([1.0, 0.5])))
        self.fall_height_m = robot.fall_height_m
        self.fall_tilt_rad = robot.fall_tilt_rad

    def _toe(self) -> np.ndarray:
        """The right sole's toe (front edge, on its centre line) at rest (world xy, m)."""
        data = mujoco.MjData(self.model)
        mujoco.mj_setState(self.model, data, self.initial_state(np.array([1.0, 0.5])),
                           mujoco.mjtState.mjSTATE_FULLPHYSICS)
        mujoco.mj_kinematics(self.model, data)
        site = data.site(self.robot.sole_site("right"))
        ax = site.xmat.reshape(3, 3)[:2, 0]
        return site.xpos[:2] + self.sole_half[0] * ax / np.linalg.norm(ax)

    def initial_state(self, ball_xy: np.ndarray, pose: np.ndarray | None = None
                      ) -> np.ndarray:
        """The scene's state: the robot at rest in its ready pose, the ball at ``ball_xy``."""
        return robot_scene.initial_state(self.model, self.robot, ball_xy)

    def foot_trajectories(self, genomes: np.ndarray, times_s: np.ndarray,
                          aims_rad: np.ndarray | float = 0.0,
                          ball_shift: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """The soles' paths (:func:`.motion.foot_trajectories`) from this robot's rest."""
        return foot_trajectories(genomes, times_s, aims_rad, rest=self.rest,
                                 retract_bulge_m=self.retract_bulge_m, ball_shift=ball_shift)

    def joint_targets(self, genomes: np.ndarray, times_s: np.ndarray,
                      aims_rad: np.ndarray | float = 0.0,
                      ball_shift: np.ndarray | None = None
                      ) -> tuple[np.ndarray, np.ndarray]:
        """Actuator targets ``[B, T, nu]`` (order ``robot.joints``) and each kick's largest
        sole distance from its planned place ``[B]`` (m; 0 when the IK reached every pose);
        ``ball_shift`` as :func:`.motion.foot_trajectories`'."""
        g = np.atleast_2d(genomes)
        feet = self.foot_trajectories(g, times_s, aims_rad, ball_shift)
        b, t = feet["right"].shape[:2]
        ctrl = np.broadcast_to(self.robot.pose, (b, t, self.robot.pose.size)).copy()
        worst = np.zeros(b)
        turn = {"left": np.broadcast_to(self.rest_rot[0], (b * t, 3, 3)),
                "right": (rot_z(feet["yaw"].ravel()) @ rot_y(feet["pitch"].ravel())
                          @ self.rest_rot[1])}
        for foot, leg in self.legs.items():
            q, err, _ = leg.solve(feet[foot].reshape(b * t, 3), turn[foot])
            ctrl[..., leg.columns] = q.reshape(b, t, -1)
            worst = np.maximum(worst, err.reshape(b, t).max(axis=1))
        return ctrl, worst

    def kick_motion(self, genome: np.ndarray, aim_rad: float = 0.0) -> Motion:
        """The whole kick of one genome as a motion of the robot's channels (20 ms poses)."""
        g = np.atleast_2d(np.asarray(genome, dtype=float))
        t = key_times(g)
        q = self.joint_targets(g, t, aim_rad)[0][0]
        return Motion(tuple(self.robot.joints), np.round(t * 1000).astype(int), q,
                      [f"Pose{i + 1}" for i in range(len(t))])
