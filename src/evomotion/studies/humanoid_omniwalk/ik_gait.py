"""The omnidirectional walk engine of :mod:`.omni_gait` for any biped, by numerical leg IK.

The NAO's engine places each ankle relative to its torso and solves the NAO's closed-form leg
IK; a robot known only by its MJCF and spec (the OP3, the dm_control humanoid, a user's
``.toml``) gets the same foot trajectories placed around its own ready pose and solved by damped
least squares on its leg chains (:class:`evomotion.sim.leg_ik.LegChain`).

**Scaling.** The gait's settings are the NAO's (:class:`.omni_gait.OmniGait`); a robot whose
ready-pose hip-to-sole height is ``L`` takes them scaled geometrically, by ``s = L / L_NAO``
(``L_NAO`` = 0.2209 m, the NAO's, :data:`NAO_HIP_TO_SOLE_M`), for lengths (step height, width,
sway, how far the walk crouches below the ready pose) and by ``√s`` for the period, which keeps
the Froude number ``v² / (g L)`` of a step of the same relative length (Alexander, "Optimization
and gaits in the locomotion of vertebrates", Physiol. Rev. 69(4), 1989: dynamically similar
gaits at equal Froude numbers). Speeds are the command's and are not scaled.

Walk frame as :mod:`.omni_gait`'s, but every foot's position is its sole's (the sole site,
``robot.sole_site``) relative to where it is in the ready pose, ``p0``:

    x = p0_x + u dx,    y = p0_y + s_f width + u dy + sway,    z = p0_z + crouch + lift H

rotated about the torso's vertical by the foot's half of the relative yaw, then into the leaning
torso's frame; the foot's orientation is the ready one turned by that yaw and the lean.

**Sway.** This engine sways quasi-statically, the torso over the stance foot (the feet shifted
towards the swing side in the torso frame): ``sway = +A cos(2π(φ − w/2) + ψ_s)``, the NAO
engine's sign flipped (``ψ_s + π``). With the NAO engine's phase, the OP3 and the dm humanoid
fell within 1-2 s in the nominal world at every sway and step height tried; with this one the OP3
walks 0.3 m/s open loop (``benchmarks/bench_omniwalk_robots.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from evomotion.sim.leg_ik import LegChain, torso_frame_feet
from evomotion.sim.robots.nao.leg_ik import rot_y, rot_z
from evomotion.studies.humanoid_omniwalk.omni_gait import OmniGait, foot_offset

#: the NAO's hip-to-sole height in its ready pose (m; ``LegChain.hip_to_sole``, a test checks)
NAO_HIP_TO_SOLE_M = 0.2209
#: the NAO's sole below its ankle (m): the engine's ``leg_height_m`` is hip to ankle
NAO_FOOT_HEIGHT_M = 0.04519
#: most an IK pose of the fitted gait may miss its foot target by (m, per unit of ``s``)
MAX_IK_ERROR_M = 0.005
#: ... and its foot orientation by (rad)
MAX_IK_ERROR_RAD = 0.05


def scaled(gait: OmniGait, scale: float) -> OmniGait:
    """``gait`` for a robot ``scale`` times the NAO's leg (lengths x s, period x √s)."""
    return replace(gait, period_s=gait.period_s * float(np.sqrt(scale)),
                   step_height_m=gait.step_height_m * scale, width_m=gait.width_m * scale,
                   sway_m=gait.sway_m * scale, x_offset_m=gait.x_offset_m * scale,
                   leg_height_m=gait.leg_height_m * scale)


@dataclass(frozen=True)
class _Foot:
    side: float  # +1 left, -1 right
    leg: LegChain
    p0: np.ndarray  # sole in the torso frame, ready pose
    r0: np.ndarray  # foot orientation in the torso frame, ready pose


class IKGait:
    """The engine for ``robot`` (a biped whose feet are named ``left`` and ``right``).

    ``gait`` is in the NAO's units; :attr:`gait` is it scaled to the robot (module doc)."""

    def __init__(self, robot, gait: OmniGait) -> None:
        from evomotion.errors import InputError

        if set(robot.spec.feet) != {"left", "right"}:
            raise InputError(f"{robot.spec.path}: the walk needs a biped with feet 'left' and "
                             f"'right' ([feet]); got {sorted(robot.spec.feet)}")
        pose = np.asarray(robot.pose, float)
        feet = torso_frame_feet(robot, pose)
        self.feet = tuple(_Foot(s, LegChain(robot, f, pose), *feet[f])
                          for s, f in ((1.0, "left"), (-1.0, "right")))
        self.hip_to_sole_m = float(self.feet[0].leg.hip_to_sole())
        self.scale = self.hip_to_sole_m / NAO_HIP_TO_SOLE_M
        self.gait = scaled(gait, self.scale)
        #: the walk's crouch: the sole this much higher (torso frame) than in the ready pose
        self.crouch_m = self.scale * (NAO_HIP_TO_SOLE_M - gait.leg_height_m - NAO_FOOT_HEIGHT_M)
        self.pose, self.name = pose, robot.name
        self.columns = np.concatenate([f.leg.columns for f in self.feet])

    def targets(self, phase: np.ndarray, command: np.ndarray) -> np.ndarray:
        """Actuator targets ``[T, nu]`` (the ready pose, legs from the IK) at ``phase[T]``
        (cycles) for ``command[T, 3]`` (vx m/s, vy m/s, ω rad/s); raises if the IK misses a
        foot target by more than :data:`MAX_IK_ERROR_M` x s (the gait does not fit the leg)."""
        from evomotion.errors import InputError

        g = self.gait
        phi = np.asarray(phase, float)
        dx, dy, dpsi = np.moveaxis(g.travel(command), -1, 0)
        w = g.swing_fraction
        u = {1.0: foot_offset(np.mod(phi, 1.0), w), -1.0: foot_offset(np.mod(phi + 0.5, 1.0), w)}
        rel_yaw = (u[1.0][0] - u[-1.0][0]) * dpsi
        sway = g.sway_m * np.cos(2 * np.pi * (phi - 0.5 * w) + g.sway_phase_rad)
        lean = np.swapaxes(rot_y(np.full(phi.shape, g.lean_rad)), -1, -2)  # walk -> torso
        out = np.broadcast_to(self.pose, phi.shape + self.pose.shape).copy()
        for f in self.feet:
            uf, lift = u[f.side]
            yaw = f.side * 0.5 * rel_yaw
            x = f.p0[0] + g.x_offset_m + uf * dx
            y = f.p0[1] + f.side * g.width_m + uf * dy + sway
            c, sn = np.cos(yaw), np.sin(yaw)
            pos = np.stack([c * x - sn * y, sn * x + c * y,
                            f.p0[2] + self.crouch_m + lift * g.step_height_m], axis=-1)
            target = (lean @ pos[..., None])[..., 0].reshape(-1, 3)
            rot = (lean @ rot_z(yaw) @ f.r0).reshape(-1, 3, 3)
            q, err, err_rad = f.leg.solve(target, rot)
            if err.size and (err.max() > MAX_IK_ERROR_M * self.scale
                             or err_rad.max() > MAX_IK_ERROR_RAD):
                raise InputError(
                    f"problem: {self.name}'s {('right', 'left')[f.side > 0]} foot misses its "
                    f"gait target by {err.max() * 1000:.1f} mm, "
                    f"{np.degrees(err_rad.max()):.1f} deg (beyond its leg's reach or joint "
                    "ranges): expected a gait it can reach; try a smaller problem.period_s, "
                    "step_height_m, width_m, sway_m, lean_rad or leg_height_m (a deeper "
                    "crouch), or "
                    "smaller command ranges (vx_min, vx_max, vy_max, yaw_rate_max)")
            out[..., f.leg.columns] = q.reshape(phi.shape + (-1,))
        return out
