"""Walk commands ``(vx, vy, ω)`` over an episode, and how well a walk tracks them.

Schedules (:func:`command_schedule`): an episode's commands come from
``numpy.random.default_rng([seed, 1])`` alone (its world from ``default_rng(seed)``,
:mod:`evomotion.studies.episode_worlds`). A new command every ``U(hold_min_s, hold_max_s)``
seconds, of one kind drawn with ``kind_weights`` (by default :data:`KIND_WEIGHTS`):
forward/backward only
(``vx ~ U(vx_min, vx_max)``), sideways only (``vy ~ U(−vy_max, vy_max)``), turning only
(``ω ~ U(−ω_max, ω_max)``), mixed (all three, each at most ``MIXED_SHARE`` of its range) or
standing (zero), as Playground's joystick tasks sample velocity commands [walking.md §4]. The
robot sees the command ramped linearly from the previous one over ``ramp_s`` (the first from
zero), as a walk engine's speed ramp (B-Human limits the acceleration, walking.md §1): a
step change of the targets would be a kick.

Tracking (:func:`tracking`): over a sliding window of one gait cycle (``window`` control steps,
so the sway averages out) the torso's displacement, rotated into the heading at the window's
middle, over the window's time is the walked velocity ``(vx, vy)``; the unwrapped yaw change over
the time is ``ω``; both beside the mean command over the same window.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: command kinds and their probabilities: forward/back, sideways, turn, mixed, stand
KIND_WEIGHTS = (0.3, 0.15, 0.15, 0.3, 0.1)
MIXED_SHARE = 0.6


@dataclass(frozen=True)
class CommandDraw:
    """The ranges commands are drawn from (m/s, rad/s, s)."""

    vx_min: float = -0.2
    vx_max: float = 0.45
    vy_max: float = 0.2
    yaw_rate_max: float = 1.2
    hold_min_s: float = 2.0
    hold_max_s: float = 4.0
    ramp_s: float = 0.5
    #: the probabilities of the kinds forward/back, sideways, turn, mixed, stand (sum 1)
    kind_weights: tuple[float, ...] = KIND_WEIGHTS


def _one(draw: CommandDraw, rng: np.random.Generator) -> np.ndarray:
    kind = int(rng.choice(len(KIND_WEIGHTS), p=draw.kind_weights))
    vx = rng.uniform(draw.vx_min, draw.vx_max)
    vy = rng.uniform(-draw.vy_max, draw.vy_max)
    w = rng.uniform(-draw.yaw_rate_max, draw.yaw_rate_max)
    if kind == 0:
        return np.array([vx, 0.0, 0.0])
    if kind == 1:
        return np.array([0.0, vy, 0.0])
    if kind == 2:
        return np.array([0.0, 0.0, w])
    if kind == 3:
        return MIXED_SHARE * np.array([vx, vy, w])
    return np.zeros(3)


def command_schedule(draw: CommandDraw, seed: int, times_s: np.ndarray,
                     preview_s: float = 0.0) -> np.ndarray:
    """The ramped commands ``[T, 3]`` of episode ``seed`` at ``times_s[T]`` (see the module
    doc); with ``preview_s`` each ramp where it will be that much later (a command's ramp is
    known once the command is given, the next command not: the ramp starts with a jump of
    ``preview_s / ramp_s`` of the change and ends ``preview_s`` sooner)."""
    rng = np.random.default_rng([int(seed), 1])
    t = np.asarray(times_s, dtype=np.float64)
    end = float(t.max()) if t.size else 0.0
    starts, cmds = [0.0], [_one(draw, rng)]
    while starts[-1] <= end:
        starts.append(starts[-1] + rng.uniform(draw.hold_min_s, draw.hold_max_s))
        cmds.append(_one(draw, rng))
    starts_a, cmds_a = np.array(starts), np.array(cmds)
    seg = np.searchsorted(starts_a, t, side="right") - 1
    prev = np.where(seg[:, None] > 0, cmds_a[np.maximum(seg - 1, 0)], 0.0)
    frac = np.clip((t - starts_a[seg] + preview_s) / draw.ramp_s, 0.0, 1.0)[:, None]
    return prev + (cmds_a[seg] - prev) * frac


def schedules(draw: CommandDraw, seeds: np.ndarray, times_s: np.ndarray,
              preview_s: float = 0.0) -> np.ndarray:
    """``[n, T, 3]``: :func:`command_schedule` of each seed (one drawn per distinct seed)."""
    seeds = np.asarray(seeds)
    cache = {int(s): command_schedule(draw, int(s), times_s, preview_s)
             for s in np.unique(seeds)}
    return np.stack([cache[int(s)] for s in seeds]) if seeds.size else \
        np.zeros((0, len(times_s), 3))


def torso_yaw(quat: np.ndarray) -> np.ndarray:
    """Yaw (rad) of ``quat[..., 4]`` (w, x, y, z), the ZYX convention."""
    w, x, y, z = np.moveaxis(quat, -1, 0)
    return np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def control_step_at(times_s: np.ndarray, control_dt_s: float, count: int) -> np.ndarray:
    """The control step ``[n]`` holding each of ``times_s[n]``, at most ``count − 1``."""
    return np.minimum((np.asarray(times_s) / control_dt_s).astype(int), count - 1)


def heading_at(torso: np.ndarray, times_s: np.ndarray, control_dt_s: float) -> np.ndarray:
    """The torso's yaw (rad) ``[n]`` at ``times_s[n]`` from a closed loop's ``torso[n, C + 1,
    7]`` record (one row per control step; the step holding the time, the last at most)."""
    c = control_step_at(times_s, control_dt_s, torso.shape[1])
    return torso_yaw(torso[np.arange(len(c)), c, 3:7])


@dataclass(frozen=True)
class Tracking:
    """Per window end ``c = window .. C`` (arrays ``[n, C + 1 − window]``): the walked ``vx``,
    ``vy`` (m/s, heading frame), ``yaw_rate`` (rad/s) and the mean command ``cmd[..., 3]``."""

    vx: np.ndarray
    vy: np.ndarray
    yaw_rate: np.ndarray
    cmd: np.ndarray

    def errors(self) -> tuple[np.ndarray, np.ndarray]:
        """(``|v − v_cmd|`` m/s, ``|ω − ω_cmd|`` rad/s) per window."""
        ev = np.hypot(self.vx - self.cmd[..., 0], self.vy - self.cmd[..., 1])
        return ev, np.abs(self.yaw_rate - self.cmd[..., 2])


def tracking(torso: np.ndarray, commands: np.ndarray, window: int, control_dt_s: float
             ) -> Tracking:
    """Walked velocities of ``torso[n, C + 1, 13]`` (a closed-loop run's) beside the commands
    ``commands[n, C, 3]`` they were given, over sliding windows of ``window`` control steps."""
    W = int(window)
    yaw = np.unwrap(torso_yaw(torso[..., 3:7]), axis=1)
    span = W * control_dt_s
    d = torso[:, W:, :2] - torso[:, :-W, :2]
    mid = yaw[:, W // 2: W // 2 + d.shape[1]]
    c, s = np.cos(mid), np.sin(mid)
    vx = (c * d[..., 0] + s * d[..., 1]) / span
    vy = (-s * d[..., 0] + c * d[..., 1]) / span
    rate = (yaw[:, W:] - yaw[:, :-W]) / span
    csum = np.concatenate([np.zeros_like(commands[:, :1]), np.cumsum(commands, axis=1)], axis=1)
    cmd = (csum[:, W:] - csum[:, :-W]) / W
    return Tracking(vx, vy, rate, cmd)
