"""Numerical leg inverse kinematics for any robot of :mod:`evomotion.sim.robots`.

The NAO has a closed-form leg IK (:mod:`evomotion.sim.robots.nao.leg_ik`); a robot known only by its
MJCF gets damped least squares on its leg's kinematic chain (Wampler, "Manipulator inverse
kinematic solutions based on vector formulations and damped least-squares methods", IEEE
Trans. SMC 16(1), 1986; Buss, "Introduction to inverse kinematics with Jacobian transpose,
pseudoinverse and damped least squares methods", 2004, eq. 11):

    dq = J^T (J J^T + lambda^2 I)^-1 e,        q <- clip(q + dq, lo, hi)

with ``e`` the sole's position error and ``ROT_WEIGHT_M`` times its orientation error
(rotation vector), solved for every pose of a batch at once (numpy, no Python loop over poses).

A leg is the chain of hinge joints from the *pelvis*, the lowest body that carries both feet
(the torso for the NAO and the OP3, the dm_control humanoid's pelvis under its abdomen
joints), down to the foot body; joints above the pelvis stay at the ready pose. Forward
kinematics follows MuJoCo's ``mj_kinematics`` for bodies and hinge joints (body ``pos`` and
``quat`` in the parent's frame, rotation by the angle less the joint's ``ref`` about the
joint axis through its anchor), in the torso's frame;
``tests/sim/test_leg_ik.py`` checks it against ``mj_kinematics``.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from evomotion.errors import InputError

ITERATIONS = 40
DAMPING = 1e-3  # lambda^2 of the damped least squares, in (m)^2
ROT_WEIGHT_M = 0.05  # an orientation error of 1 rad weighs like this many metres
TOLERANCE_M = 1e-7  # a pose whose weighted errors are all below this is solved
STALL_RAD = 1e-6  # a pose whose joints move less than this in an iteration has stalled


def _quat_mat(q: np.ndarray) -> np.ndarray:
    m = np.empty(9)
    mujoco.mju_quat2Mat(m, np.asarray(q, float))
    return m.reshape(3, 3)


def _axis_rot(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotations ``[N, 3, 3]`` by ``angle[N]`` about the unit ``axis[3]`` (Rodrigues)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]],
                  [-axis[1], axis[0], 0.0]])
    s, c = np.sin(angle)[:, None, None], np.cos(angle)[:, None, None]
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


def rotation_vector(r: np.ndarray) -> np.ndarray:
    """Rotation vectors ``[N, 3]`` (axis times angle) of rotation matrices ``r[N, 3, 3]``."""
    v = np.stack([r[:, 2, 1] - r[:, 1, 2], r[:, 0, 2] - r[:, 2, 0], r[:, 1, 0] - r[:, 0, 1]],
                 axis=1)
    s = 0.5 * np.linalg.norm(v, axis=1)
    c = np.clip(0.5 * (np.trace(r, axis1=1, axis2=2) - 1.0), -1.0, 1.0)
    angle = np.arctan2(s, c)
    scale = np.where(s > 1e-12, angle / np.maximum(2.0 * s, 1e-300), 0.5)
    return v * scale[:, None]


@dataclass(frozen=True)
class _Link:
    pos: np.ndarray  # body position in its parent's frame
    rot: np.ndarray  # body orientation in its parent's frame [3, 3]
    joints: tuple[tuple[np.ndarray, np.ndarray, float], ...]  # (anchor, axis, ref) in the
    # body frame; MuJoCo turns a hinge by its angle minus the reference angle qpos0 (``ref``)


class LegChain:
    """One leg of a robot: FK and batched damped-least-squares IK of its sole.

    ``joints``: the hinge joints from the pelvis to the foot (names), ``columns`` their
    actuator columns, ``lower``/``upper`` their ranges; poses and targets are in the torso's
    frame with every joint above the pelvis at the ready pose ``pose`` (actuator targets)."""

    def __init__(self, robot, foot: str, pose: np.ndarray) -> None:
        m = robot.model
        torso = m.body(robot.spec.torso).id
        foot_body = m.body(robot.spec.feet[foot]).id
        pelvis = _pelvis(m, [m.body(b).id for b in robot.spec.feet.values()])
        chain = []
        b = foot_body
        while b != pelvis:
            chain.append(b)
            b = int(m.body_parentid[b])
            if b == 0:
                raise InputError(f"{robot.spec.path}: foot {foot!r} does not hang from the "
                                 "torso")
        chain.reverse()
        data = _kinematics(robot, pose)
        r_t = data.xmat[torso].reshape(3, 3)
        # the pelvis in the torso's frame (fixed: joints above it stay at the ready pose)
        self.base_pos = r_t.T @ (data.xpos[pelvis] - data.xpos[torso])
        self.base_rot = r_t.T @ data.xmat[pelvis].reshape(3, 3)
        links, names = [], []
        for body in chain:
            js = []
            for j in range(int(m.body_jntadr[body]),
                           int(m.body_jntadr[body]) + int(m.body_jntnum[body])):
                name = m.joint(j).name
                if m.jnt_type[j] != mujoco.mjtJoint.mjJNT_HINGE:
                    raise InputError(f"{robot.spec.path}: leg joint {name!r} of foot "
                                     f"{foot!r} is not a hinge (the leg IK needs hinges)")
                if name not in robot.joints:
                    raise InputError(f"{robot.spec.path}: leg joint {name!r} of foot "
                                     f"{foot!r} has no actuator")
                js.append((m.jnt_pos[j].copy(), m.jnt_axis[j].copy(),
                           float(m.qpos0[m.jnt_qposadr[j]])))
                names.append(name)
            links.append(_Link(m.body_pos[body].copy(), _quat_mat(m.body_quat[body]),
                               tuple(js)))
        if not names:
            raise InputError(f"{robot.spec.path}: foot {foot!r} has no leg joints")
        self.links = tuple(links)
        self.joints = tuple(names)
        self.columns = np.array([robot.joints.index(n) for n in names], dtype=np.int64)
        lo = robot.model.actuator_ctrlrange[self.columns, 0]
        hi = robot.model.actuator_ctrlrange[self.columns, 1]
        limited = robot.model.actuator_ctrllimited[self.columns].astype(bool)
        self.lower = np.where(limited, lo, -np.pi)
        self.upper = np.where(limited, hi, np.pi)
        site = m.site(robot.sole_site(foot)).id
        self.sole = m.site_pos[site].copy()  # in the foot body's frame
        self.ready = pose[self.columns].copy()

    def fk(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Sole position ``[N, 3]`` and foot orientation ``[N, 3, 3]`` in the torso frame of
        joint angles ``q[N, n]``, with each joint's anchor and world axis ``[N, n, 3]``."""
        q = np.atleast_2d(q)
        n = len(q)
        pos = np.broadcast_to(self.base_pos, (n, 3)).copy()
        rot = np.broadcast_to(self.base_rot, (n, 3, 3)).copy()
        anchors, axes = [], []
        k = 0
        for link in self.links:
            pos = pos + rot @ link.pos
            rot = rot @ link.rot
            for jpos, jaxis, ref in link.joints:
                anchor = pos + rot @ jpos
                axes.append(rot @ jaxis)
                anchors.append(anchor)
                rot = rot @ _axis_rot(jaxis, q[:, k] - ref)
                pos = anchor - rot @ jpos
                k += 1
        sole = pos + rot @ self.sole
        return sole, rot, np.stack(anchors, 1), np.stack(axes, 1)

    def hip_to_sole(self) -> float:
        """Vertical distance [m] from the hip (the lowest anchor of the leg's first half of
        joints: hip yaw, roll and pitch of a 6-joint leg) to the sole in the ready pose: the
        robot's leg length, by which the studies scale motions made for the NAO."""
        sole, _, anchors, _ = self.fk(self.ready[None])
        hip = anchors[0, :max(1, len(self.joints) // 2), 2].min()
        return float(hip - sole[0, 2])

    def solve(self, target_pos: np.ndarray, target_rot: np.ndarray,
              q0: np.ndarray | None = None, iterations: int = ITERATIONS
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Joint angles ``[N, n]`` that put the sole at ``target_pos[N, 3]`` with the foot
        at ``target_rot[N, 3, 3]`` (torso frame), from ``q0`` (default: the ready pose),
        within the joint ranges; with the remaining position error [m] and orientation
        error [rad] of each pose."""
        target_pos = np.atleast_2d(target_pos)
        n = len(target_pos)
        q = np.broadcast_to(self.ready if q0 is None else q0,
                            (n, len(self.joints))).astype(float, copy=True)
        target_rot = np.broadcast_to(target_rot, (n, 3, 3))
        eye = DAMPING * np.eye(6)
        active = np.arange(n)  # the poses not yet within TOLERANCE_M (each step is per pose)
        for _ in range(iterations):
            e, jac = self._residual(q[active], target_pos[active], target_rot[active])
            moving = np.abs(e).max(axis=1) > TOLERANCE_M
            active, e, jac = active[moving], e[moving], jac[moving]
            if not active.size:
                break
            jjt = jac @ jac.transpose(0, 2, 1) + eye
            dq = (jac.transpose(0, 2, 1) @ np.linalg.solve(jjt, e[..., None]))[..., 0]
            new = np.clip(q[active] + dq, self.lower, self.upper)
            still = np.abs(new - q[active]).max(axis=1) > STALL_RAD  # else: as near as it gets
            q[active] = new
            active = active[still]
        e, _ = self._residual(q, target_pos, target_rot)
        return q, np.linalg.norm(e[:, :3], axis=1), np.linalg.norm(e[:, 3:], axis=1) / \
            ROT_WEIGHT_M

    def _residual(self, q: np.ndarray, target_pos: np.ndarray, target_rot: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
        sole, rot, anchors, axes = self.fk(q)
        e_rot = rotation_vector(target_rot @ rot.transpose(0, 2, 1))
        e = np.concatenate([target_pos - sole, ROT_WEIGHT_M * e_rot], axis=1)
        jp = np.cross(axes, sole[:, None, :] - anchors)  # [N, n, 3]
        jac = np.concatenate([jp, ROT_WEIGHT_M * axes], axis=2).transpose(0, 2, 1)
        return e, jac


def _pelvis(m: mujoco.MjModel, feet: list[int]) -> int:
    """The lowest body that is an ancestor of every foot."""
    def ancestors(b: int) -> list[int]:
        out = [b]
        while b != 0:
            b = int(m.body_parentid[b])
            out.append(b)
        return out

    common = set(ancestors(feet[0]))
    for f in feet[1:]:
        common &= set(ancestors(f))
    return next(b for b in ancestors(feet[0]) if b in common)


def _kinematics(robot, pose: np.ndarray) -> mujoco.MjData:
    """MjData of the robot's initial state with its actuated joints at ``pose[nu]``, after
    ``mj_kinematics``."""
    m = robot.model
    data = mujoco.MjData(m)
    mujoco.mj_setState(m, data, robot.state0, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    for a, name in enumerate(robot.joints):
        if m.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT:
            data.qpos[m.jnt_qposadr[m.joint(name).id]] = pose[a]
    mujoco.mj_kinematics(m, data)
    return data


def torso_frame_feet(robot, pose: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Each foot's sole position and orientation in the torso frame at ``pose``
    (``mj_kinematics``)."""
    m = robot.model
    data = _kinematics(robot, pose)
    torso = m.body(robot.spec.torso).id
    r_t = data.xmat[torso].reshape(3, 3)
    out = {}
    for foot, body in robot.spec.feet.items():
        site = m.site(robot.sole_site(foot)).id
        out[foot] = (r_t.T @ (data.site_xpos[site] - data.xpos[torso]),
                     r_t.T @ data.xmat[m.body(body).id].reshape(3, 3))
    return out
