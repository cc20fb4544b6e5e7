"""The repertoire's step (:mod:`.step`) solved by a numerical leg IK: any biped.

The same genes and phases as the NAO's step (:func:`.step.foot_plan`): shift the weight over
the stance foot, swing the lead foot to its new place, carry the torso over it, swing the
other foot beside it, shift back. The feet start where the robot's ready pose (its spec's
initial pose) puts them, and every key pose is solved by the numerical leg IK of
:mod:`evomotion.sim.leg_ik` (torso level at its ready height, feet flat and turned by
their yaw), for all key poses of a batch of genomes at once. The hip yaw-pitch coupling of the
NAO does not exist here: each leg is solved on its own.

Size: ``sway_m`` (the torso's shift over a stance foot) scales with the half-distance of the
robot's feet over the NAO's (:data:`NAO_HALF_WIDTH_M`); the other lengths (``dx_m``,
``dy_m``, ``step_height_m`` and the measure box) with ``s`` = the robot's hip-to-sole height
in its ready pose over the NAO's in its repertoire ready pose (:data:`NAO_HIP_TO_SOLE_M`; the
hip: the lowest anchor of the leg's first half of joints, its hip yaw, roll and pitch for a
6-joint leg); durations with ``sqrt(s)`` (Froude similarity: walking keeps its shape when time
scales with the square root of length); angles do not scale. The genes keep the NAO's names.
"""

from __future__ import annotations

import math

import numpy as np

from evomotion.core.problem import MeasureSpec
from evomotion.sim.leg_ik import LegChain, torso_frame_feet
from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.leg_ik import rot_z
from evomotion.studies.humanoid_repertoire import step

#: the NAO's repertoire ready pose: hip joints to ankle (vertical) plus ankle to sole [m]
NAO_HIP_TO_SOLE_M = step.LEG_HEIGHT_M + nao.FOOT_HEIGHT_M
#: the NAO's repertoire ready pose: half the distance between its feet [m]
NAO_HALF_WIDTH_M = step.HIP_Y_M + step.WIDTH_M
LENGTH_GENES = ("dx_m", "dy_m", "step_height_m")
TIME_GENES = ("shift_s", "swing_s")


def hip_to_sole(leg: LegChain) -> float:
    """Vertical distance [m] from the hip (the lowest anchor of the leg's first half of
    joints) to the sole in the ready pose."""
    sole, _, anchors, _ = leg.fk(leg.ready[None])
    hip = anchors[0, :max(1, len(leg.joints) // 2), 2].min()
    return float(hip - sole[0, 2])


class RobotStep:
    """Key poses of repertoire steps on ``robot`` (a :class:`~evomotion.sim.robots.Robot` with
    feet ``left`` and ``right``)."""

    def __init__(self, robot) -> None:
        self.pose = robot.pose
        self.feet0 = torso_frame_feet(robot, robot.pose)
        self.legs = {f: LegChain(robot, f, robot.pose) for f in ("left", "right")}
        self.scale = float(np.mean([hip_to_sole(leg) for leg in self.legs.values()])
                           / NAO_HIP_TO_SOLE_M)
        factor = np.ones(len(step.NAMES))
        for n in LENGTH_GENES:
            factor[step.INDEX[n]] = self.scale
        for n in TIME_GENES:
            factor[step.INDEX[n]] = math.sqrt(self.scale)
        half_width = 0.5 * abs(self.feet0["left"][0][1] - self.feet0["right"][0][1])
        factor[step.INDEX["sway_m"]] = half_width / NAO_HALF_WIDTH_M
        self.lower, self.upper = step.LOWER * factor, step.UPPER * factor
        self.default = step.DEFAULT * factor
        sh, sw = step.durations_ms(self.upper)  # the longest phases, on the pose grid
        self.max_duration_s = (3 * sh + 2 * sw) / 1000.0

    def measure_box(self, nao: MeasureSpec) -> MeasureSpec:
        """The NAO's measure box with its lengths scaled to this robot."""
        f = np.array([self.scale, self.scale, 1.0])
        return MeasureSpec(nao.names, nao.lower * f, nao.upper * f, nao.bins)

    def poses(self, genomes: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
        """Key poses ``[K_i, nu]`` every 20 ms of each genome's step (ready pose to ready
        pose), and the largest sole error [m] of the IK in each step ``[P]``."""
        genomes = np.atleast_2d(genomes)
        plans = []
        for g in genomes:
            plans.append(step.foot_plan(g, self.feet0["left"][0][:2],
                                        self.feet0["right"][0][:2]))
        sizes = [p.t.size for p in plans]
        out = [np.broadcast_to(self.pose, (k, self.pose.size)).copy() for k in sizes]
        rows = np.repeat(np.arange(len(plans)), sizes)
        worst = np.zeros(len(plans))
        for foot in ("left", "right"):
            pos0, rot0 = self.feet0[foot]
            targets, yaws = [], []
            for p in plans:
                xy, yaw, lift = p.lead if (foot == "left") == p.lead_is_left else p.other
                rel = step._rot(-p.yaw, xy - p.torso)
                targets.append(np.stack([rel[:, 0], rel[:, 1], pos0[2] + lift], -1))
                yaws.append(yaw - p.yaw)
            leg = self.legs[foot]
            q, err, _ = leg.solve(np.concatenate(targets), rot_z(np.concatenate(yaws)) @ rot0)
            np.maximum.at(worst, rows, err)
            for i, part in enumerate(np.split(q, np.cumsum(sizes)[:-1])):
                out[i][:, leg.columns] = part
        return out, worst

    def padded(self, genomes: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Key poses padded with each step's last pose to a common grid ``[P, K, nu]``, the
        grid's times [s], each step's duration [s] ``[P]`` and its IK error [m] ``[P]``."""
        poses, worst = self.poses(genomes)
        k = max(len(p) for p in poses)
        out = np.empty((len(poses), k, self.pose.size))
        for i, p in enumerate(poses):
            out[i, :len(p)], out[i, len(p):] = p, p[-1]
        durations = np.array([(len(p) - 1) * step.POSE_MS / 1000.0 for p in poses])
        return out, np.arange(k) * step.POSE_MS / 1000.0, durations, worst
