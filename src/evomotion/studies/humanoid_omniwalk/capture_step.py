"""Capture-point foot placement on top of the walk controller (``problem.capture_gain``).

Every control step the torso's horizontal velocity is estimated from the robot's own sensors
by leg odometry: a stance foot does not move, so in the torso frame

    v = −(ω × p(q) + J(q) q̇)                                                    (1)

with ``p(q)`` the ankle's position from the closed-form leg kinematics
(:func:`evomotion.sim.robots.nao.leg_ik.leg_fk`), ``q``, ``q̇`` the leg's servo angles and
velocities, ``ω`` the gyro; both feet's estimates are averaged over the feet in contact (the
gait clock's stance feet when neither touches). The hip yaw-pitch motor, not among the
walk's observations, is taken at its last target, its velocity the targets' rate (without
it, turning at 1 rad/s roughly doubles the estimate's forward error, 8.3 against 4.4 cm/s, a
review's measurement). Its velocity offset from the undisturbed walk,

    Δv = v − (vx, vy)_command − v̄(φ)                                            (2)

with ``v̄(φ)`` the walk's own sway by gait phase, learnt online per episode (a running mean
per control step of the cycle, rate ``CALIBRATION_RATE``, not updated while ``|Δv|`` exceeds
``CALIBRATION_GATE_MPS``: a bin whose own sway exceeds it stays unlearnt, as with the
fitted engine's 0.3 m/s sway; the layer acts after ``WARMUP_CYCLES``), less a dead band
(``|Δv|`` shrunk by ``DEADBAND_MPS``: the walk's own noise moves no foot), moves the capture
point by ``Δv / ω₀`` (Pratt et al., "Capture Point: A Step toward Humanoid Push Recovery",
Humanoids 2006; ``ω₀ = √(g / z_com)``, the CoM's height in the nominal pose). The swinging
foot's landing point moves there by ``gain · Δv / ω₀`` (clipped to ``REACH_X_M`` forward and back,
``OUT_Y_M`` outward, ``IN_Y_M`` inward), blended from its offset at lift-off along the swing's
cosine; a stance foot keeps its offset. The walk engine (:func:`.omni_gait.targets`,
``foot_offsets``) turns the offsets into joint offsets, added to the controller's action.

``benchmarks/walk_capture_step.py`` measures it against the true velocity (an oracle) and the
plain controller. The NAO only (its closed-form leg kinematics and engine).
"""

from __future__ import annotations

import math

import numpy as np

REACH_X_M, OUT_Y_M, IN_Y_M = 0.10, 0.08, 0.01
CALIBRATION_RATE = 0.3  # per visit of a phase bin (once a cycle)
CALIBRATION_GATE_MPS = 0.2
WARMUP_CYCLES = 3
#: ``|Δv|`` below this is the walk's own noise (the estimate's, the tracking's lag) and moves
#: no foot; above it, the excess does (scanned: 0.1 and 0.2 m/s, docs/humanoid-walk.md)
DEADBAND_MPS = 0.2
_LEG = ("HipRoll", "HipPitch", "KneePitch", "AnklePitch", "AnkleRoll")
_HALF_CYCLE = np.array([0.0, 0.5])  # the feet's phases: left φ, right φ + 1/2
_SIDE = np.array([1.0, -1.0])  # left, right: outward is +y, -y


def com_height(robot, state: np.ndarray) -> float:
    """The CoM's height (m) above the floor of ``robot`` in ``state`` (a ``state_at``)."""
    import mujoco

    from evomotion.sim.state import QPOS_OFFSET

    m = robot.model
    d = mujoco.MjData(m)
    d.qpos[:] = state[QPOS_OFFSET:QPOS_OFFSET + m.nq]
    mujoco.mj_forward(m, d)
    return float(d.subtree_com[1][2])


class LegOdometry:
    """Eq. (1) over rows of the walk's observation (names ``names``)."""

    def __init__(self, names: list[str], swing_fraction: float) -> None:
        self.pos = [[names.index(f"joint_pos:{s}{j}") for j in _LEG] for s in "LR"]
        self.vel = [[names.index(f"joint_vel:{s}{j}") for j in _LEG] for s in "LR"]
        self.gyro = [names.index(f"gyro:{a}") for a in "xyz"]
        self.contact = [names.index("foot_contact:left"), names.index("foot_contact:right")]
        self.swing_fraction = float(swing_fraction)

    def __call__(self, obs: np.ndarray, phase: np.ndarray, hip_yaw_pitch: np.ndarray,
                 hip_yaw_pitch_rate: np.ndarray) -> np.ndarray:
        """``v[n, 2]`` (m/s, torso frame x, y) of ``obs[n, o]`` at gait ``phase[n]``, the hip
        yaw-pitch at ``hip_yaw_pitch[n]`` (rad) moving at ``hip_yaw_pitch_rate[n]`` (rad/s)."""
        from evomotion.sim.robots.nao.leg_ik import ankle_position

        w, eps, est, n = obs[:, self.gyro], 1e-4, [], len(obs)
        for f in range(2):
            q = np.concatenate([hip_yaw_pitch[:, None], obs[:, self.pos[f]]], axis=1)
            dq = np.concatenate([hip_yaw_pitch_rate[:, None], obs[:, self.vel[f]]], axis=1)
            # p(q) and p(q + ε q̇) in one call (row by row the same numbers as two)
            p = ankle_position(np.concatenate([q, q + eps * dq]), left=f == 0)
            p0, p1 = p[:n], p[n:]
            # x, y of −(ω × p + J q̇): np.cross's products and differences, written out
            est.append(-(np.stack([w[:, 1] * p0[:, 2] - w[:, 2] * p0[:, 1],
                                   w[:, 2] * p0[:, 0] - w[:, 0] * p0[:, 2]], axis=1)
                         + (p1[:, :2] - p0[:, :2]) / eps))
        stance = np.stack([phase % 1.0 >= self.swing_fraction,
                           (phase + 0.5) % 1.0 >= self.swing_fraction], axis=1)
        touch = obs[:, self.contact] > 0.5
        weight = np.where(touch.any(axis=1, keepdims=True), touch, stance).astype(float)
        weight /= np.maximum(weight.sum(axis=1, keepdims=True), 1.0)
        # a foot not counted adds nothing, even a non-finite estimate (0 x NaN would be NaN)
        return (np.where(weight[:, :1] > 0, weight[:, :1] * est[0], 0.0)
                + np.where(weight[:, 1:] > 0, weight[:, 1:] * est[1], 0.0))


class CaptureStep:
    """The layer (module doc) for ``n`` episodes of ``ctl`` (a :class:`.controller.Controller`
    on the NAO) reading observations named ``names``: ``layer(rows, obs, action)`` returns the
    action with the feet moved. ``velocity``: observation columns of a true torso velocity to
    use instead of eq. (1) (an oracle, for benchmarks); ``sway``: a fixed ``v̄[bins, 2]``
    instead of learning it online; ``deadband_mps`` over ``DEADBAND_MPS``. Its state is per
    episode (``rows`` index it)."""

    def __init__(self, ctl, names: list[str], n: int, gain: float,
                 velocity: list[int] | None = None, sway: np.ndarray | None = None,
                 deadband_mps: float = DEADBAND_MPS) -> None:
        self.ctl, self.gain, self.velocity = ctl, float(gain), velocity
        self.deadband = float(deadband_mps)
        self.odometry = LegOdometry(names, ctl.gait.swing_fraction)
        self.iph = names.index("phase:sin"), names.index("phase:cos")
        self.ic = [names.index(f"command:{i}") for i in range(3)]
        self.omega = math.sqrt(9.81 / ctl.com_height_m)
        self.bins = ctl.window  # control steps per gait cycle
        self.fixed = sway is not None
        self.sway = (np.broadcast_to(sway, (n, self.bins, 2)).copy() if sway is not None
                     else np.zeros((n, self.bins, 2)))
        self.steps = np.zeros(n, np.int64)
        self.offset, self.lift_off = np.zeros((n, 2, 2)), np.zeros((n, 2, 2))
        self.swinging = np.zeros((n, 2), bool)
        self.hyp_col = list(ctl.driven).index("LHipYawPitch")
        self.hip_yaw_pitch = np.full(n, ctl.nominal[ctl.columns[self.hyp_col]])
        self.hip_yaw_pitch_rate = np.zeros(n)

    def phase(self, obs: np.ndarray) -> np.ndarray:
        return np.arctan2(obs[:, self.iph[0]], obs[:, self.iph[1]]) / (2 * np.pi) % 1.0

    def velocity_of(self, rows: np.ndarray, obs: np.ndarray, phase: np.ndarray) -> np.ndarray:
        """The torso's ``v[n, 2]`` (eq. 1, or the oracle's columns)."""
        if self.velocity is not None:
            return obs[:, self.velocity]
        return self.odometry(obs, phase, self.hip_yaw_pitch[rows],
                             self.hip_yaw_pitch_rate[rows])

    def __call__(self, rows: np.ndarray, obs: np.ndarray, action: np.ndarray) -> np.ndarray:
        from evomotion.studies.humanoid_omniwalk.omni_gait import targets

        ctl, gait = self.ctl, self.ctl.gait
        phase, command = self.phase(obs), obs[:, self.ic]
        b = np.round(phase * self.bins).astype(np.int64) % self.bins
        sway = self.sway[rows, b]
        v = self.velocity_of(rows, obs, phase)
        dv = v - command[:, :2] - sway  # eq. (2)
        # a non-finite reading moves no foot and learns no sway
        dv = np.where(np.isfinite(dv).all(axis=1, keepdims=True), dv, 0.0)
        self.steps[rows] += 1
        if not self.fixed:
            calm = np.linalg.norm(dv, axis=1) < CALIBRATION_GATE_MPS
            self.sway[rows, b] = np.where(calm[:, None], sway + CALIBRATION_RATE * dv, sway)
            dv = np.where((self.steps[rows] > WARMUP_CYCLES * self.bins)[:, None], dv, 0.0)
        size = np.linalg.norm(dv, axis=1, keepdims=True)
        dv = dv * np.maximum(size - self.deadband, 0.0) / np.maximum(size, 1e-12)
        land = self.gain * dv / self.omega
        off, lift_off = self.offset[rows], self.lift_off[rows]  # [n, foot, (x, y)]
        w, ahead = gait.swing_fraction, ctl.control_dt / gait.period_s
        p = (phase[:, None] + _HALF_CYCLE) % 1.0  # each foot's phase [n, foot]
        swing = p < w
        lift_off = np.where((swing & ~self.swinging[rows])[..., None], off, lift_off)
        goal = np.stack([np.broadcast_to(np.clip(land[:, :1], -REACH_X_M, REACH_X_M), p.shape),
                         _SIDE * np.clip(_SIDE * land[:, 1:], -IN_Y_M, OUT_Y_M)], axis=-1)
        a = 0.5 * (1.0 - np.cos(np.pi * np.clip((p + ahead) / w, 0.0, 1.0)))
        moving = lift_off + (goal - lift_off) * a[..., None]
        off = np.where(swing[..., None], moving, off)
        self.swinging[rows] = swing
        self.offset[rows], self.lift_off[rows] = off, lift_off
        # the engine with the feet moved less without, in one call on both sets of rows (row
        # by row the same numbers as two calls), on the rows whose feet are moved or whose
        # phase or command is not finite (NaN less NaN is NaN, as the ONNX layer gives): on
        # the others offsets of zero add exactly nothing (the same targets twice)
        moved = np.zeros_like(action)
        m = np.flatnonzero((off != 0.0).any(axis=(1, 2)) | ~np.isfinite(phase)
                           | ~np.isfinite(command).all(axis=1))
        if m.size:
            k = m.size
            both = targets(gait, np.concatenate([phase[m], phase[m]]),
                           np.concatenate([command[m], command[m]]),
                           np.concatenate([np.zeros_like(off[m]), off[m]]))
            moved[m] = (both[k:] - both[:k])[:, ctl.columns]
        out = action + moved
        hyp = ctl.nominal[ctl.columns[self.hyp_col]] + out[:, self.hyp_col]
        ok = np.isfinite(hyp)  # a NaN action: the motor holds its last target
        self.hip_yaw_pitch_rate[rows] = np.where(
            ok, (hyp - self.hip_yaw_pitch[rows]) / ctl.control_dt, 0.0)
        self.hip_yaw_pitch[rows] = np.where(ok, hyp, self.hip_yaw_pitch[rows])
        return out
