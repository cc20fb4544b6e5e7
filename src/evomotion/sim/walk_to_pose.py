"""Walk a robot to a pose with a closed-loop walk controller (issue 34): the go-to-pose law
that turns a target pose into the controller's command, and the loop that plays it in one
MuJoCo simulation (any model holding the robot: the NAO alone, or beside a ball).

Every control period of the :class:`~evomotion.sim.policy_player.PolicyPlayer`:

- the torso position (x, y) is averaged over the last gait period (the walk's lateral sway, a
  few centimetres, would otherwise make the command oscillate); the heading is the current one
  (an averaged heading lags and the turn overshoots);
- intermediate waypoints are passed within ``PASS_M``, walking forward towards each;
- towards the last one, :func:`command_to`: far from it (> ``FAR_M``) the robot turns to the
  goal point and walks forward (a walk's fastest direction), near it it turns to the goal
  heading and corrects x and y omnidirectionally; each component proportional to its error
  (gains ``K_XY`` 1/s, ``K_YAW`` 1/s) and clipped to ``SPEED_SCALE`` x the controller's
  command ranges;
- it stops at a moment when **both feet are down** (for more than ``SETTLED_STEPS`` control
  periods, or for one where the gait's double support over the last two gait periods did not
  last longer) and the soles' midpoint and mean heading are
  within ``tol_m`` / ``tol_deg`` of where the caller wants the feet (where they stay when the
  robot stops), or after ``max_s``; the caller then moves the targets to its standing pose.
  A controller that hovers around the goal without meeting the tolerances (its sideways and
  turning tracking too coarse) is let go: after ``WIDEN_S`` seconds within ``FAR_M``, both
  tolerances grow by their own size every further ``WIDEN_S`` seconds.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco
import numpy as np

from evomotion.core.angles import wrap_angle as wrap
from evomotion.errors import InputError
from evomotion.sim.policy_player import PolicyPlayer
from evomotion.sim.rollout import fall_step, torso_track
from evomotion.sim.state import QPOS_OFFSET

FAR_M = 0.35
PASS_M = 0.15
K_XY, K_YAW = 1.5, 2.0
SPEED_SCALE = 0.8  # of each command range: a margin below the controller's top speeds
#: both feet down for more than this many control periods before a stop (the first period of
#: double support still carries the landing: stopping then moved the NAO's soles 1-1.5 cm and
#: 2 deg while it crouched, against 0.3 cm after one more period)
SETTLED_STEPS = 1
WIDEN_S = 2.0  # near the goal, the tolerances grow by themselves every this many seconds


def settle_periods(streaks: list[int]) -> int:
    """The control periods of double support a stop waits beyond the first: ``SETTLED_STEPS``,
    or fewer for a gait whose double support over the window never lasted longer (``streaks``:
    its length so far at each of the last control periods; a mirror-symmetric controller's
    lasts one period, and it hovered until ``max_s``); a window without a step (no 0: a
    standing start) keeps ``SETTLED_STEPS``."""
    if 0 not in streaks:
        return SETTLED_STEPS
    return min(SETTLED_STEPS, max(max(streaks) - 1, 0))


def command_to(pose: np.ndarray, goal: np.ndarray, vmax: np.ndarray,
               passing: bool = False) -> np.ndarray:
    """The go-to-pose command (vx, vy, yaw rate) from ``pose`` to ``goal`` (x, y, heading;
    m, rad): ``vmax`` = (forward, sideways, yaw rate, backward) maxima. ``passing``: a
    waypoint to walk through (face it and walk, whatever the distance)."""
    d = goal[:2] - pose[:2]
    c, s = math.cos(pose[2]), math.sin(pose[2])
    if passing or float(np.hypot(*d)) > FAR_M:  # face the goal point and walk
        yaw_err = wrap(math.atan2(d[1], d[0]) - pose[2])
        vx, vy = vmax[0] * max(0.0, math.cos(yaw_err)) ** 2, 0.0
    else:
        yaw_err = wrap(goal[2] - pose[2])
        vx, vy = K_XY * (c * d[0] + s * d[1]), K_XY * (-s * d[0] + c * d[1])
    return np.array([float(np.clip(vx, -vmax[3], vmax[0])), float(np.clip(vy, -vmax[1], vmax[1])),
                     float(np.clip(K_YAW * yaw_err, -vmax[2], vmax[2]))])


def command_limits(player: PolicyPlayer, where: str) -> np.ndarray:
    """(forward, sideways, yaw rate, backward) maxima of a walk controller's command ranges,
    times ``SPEED_SCALE``; ``where`` names the controller in the error."""
    r = player.command_ranges
    if set(r) != {"vx", "vy", "yaw_rate"}:
        raise InputError(f"{where}: expected the command ranges of a walk (vx, vy, yaw_rate), "
                         f"got {', '.join(r) or 'none'}")
    return SPEED_SCALE * np.array([r["vx"][1], min(-r["vy"][0], r["vy"][1]),
                                   min(-r["yaw_rate"][0], r["yaw_rate"][1]),
                                   max(-r["vx"][0], 0.0)])


@dataclass
class Walker:
    """One robot walking in ``data``: ``torso(data) -> (x, y, heading)``, ``feet(data) ->
    (x, y, heading)`` of the soles, ``contacts``: sensor addresses (one per foot; > 0 while it
    touches), ``fallen(data) -> bool``; every physics step's ``qpos`` goes to ``frames``."""

    model: mujoco.MjModel
    data: mujoco.MjData
    player: PolicyPlayer
    torso: Callable[[mujoco.MjData], np.ndarray]
    feet: Callable[[mujoco.MjData], np.ndarray]
    contacts: list[int]
    fallen: Callable[[mujoco.MjData], bool]
    frames: list[np.ndarray] = field(default_factory=list)

    def hold(self, ctrl: np.ndarray, steps: int) -> None:
        self.data.ctrl[:] = ctrl
        for _ in range(int(steps)):
            mujoco.mj_step(self.model, self.data)
            self.frames.append(self.data.qpos.copy())

    def ramp(self, a: np.ndarray, b: np.ndarray, seconds: float) -> None:
        """Targets moved linearly from ``a`` to ``b`` over ``seconds``."""
        n = max(1, round(seconds / self.model.opt.timestep))
        for i in range(1, n + 1):
            self.hold(a + (b - a) * (i / n), 1)

    def walk(self, goals: np.ndarray, feet_goal: np.ndarray, vmax: np.ndarray,
             tol_m: float = 0.01, tol_deg: float = 2.0, max_s: float = 20.0
             ) -> tuple[float, bool]:
        """Walk through the torso waypoints ``goals[k, 3]`` (the last one the goal) until the
        feet are at ``feet_goal`` (see the module doc): (seconds walked, reached)."""
        d, p = self.data, self.player
        p.start(d)
        k, dt = p.control_steps, self.model.opt.timestep
        per_period = max(1, round(p.period_s / p.control_dt))
        recent: list[np.ndarray] = []
        i, walked, near_s, both = 0, 0.0, 0.0, 0
        streaks: list[int] = []  # double support's length, every control period
        counted = -1.0  # the time of the last period counted (a waypoint passed: no step)
        while walked < max_s and not self.fallen(d):
            down = all(d.sensordata[a] > 0 for a in self.contacts)
            if walked != counted:
                streaks = (streaks + [streaks[-1] + 1 if down and streaks else int(down)]
                           )[-2 * per_period:]
                counted = walked
            now = self.torso(d)
            recent = (recent + [now[:2]])[-per_period:]
            pose = np.array([*np.mean(recent, axis=0), now[2]])
            target = goals[i]
            passing = i < len(goals) - 1
            if passing:
                if np.hypot(*(target[:2] - pose[:2])) < PASS_M:
                    i += 1
                    continue
            else:
                if np.hypot(*(target[:2] - pose[:2])) < FAR_M:
                    near_s += k * dt
                grow = 1.0 + max(near_s - WIDEN_S, 0.0) / WIDEN_S  # hovering: let go
                feet = self.feet(d)
                both = both + 1 if down else 0
                if (both > settle_periods(streaks)
                        and np.hypot(*(feet[:2] - feet_goal[:2])) < tol_m * grow
                        and abs(math.degrees(wrap(feet[2] - feet_goal[2]))) < tol_deg * grow):
                    return walked, True
            self.hold(p.targets(d, command_to(pose, target, vmax, passing)), k)
            walked += k * dt
        return walked, False


def _track(data: mujoco.MjData):
    """The torso track of :mod:`evomotion.sim.rollout` for ``data``'s state now (one row)."""
    state = np.zeros(QPOS_OFFSET + 7)
    state[QPOS_OFFSET:] = data.qpos[:7]
    return torso_track(state[None, None])


def torso_pose(data: mujoco.MjData) -> np.ndarray:
    """(x, y, heading) of the free joint (the model's first joint: the robot's torso)."""
    t = _track(data)
    return np.array([t.xyz[0, 0, 0], t.xyz[0, 0, 1], t.yaw_rad[0, 0]])


def fallen_test(height_m: float, tilt_rad: float) -> Callable[[mujoco.MjData], bool]:
    """``fallen(data)``: the torso (free joint) below ``height_m`` or tilted beyond
    ``tilt_rad``, by :func:`evomotion.sim.rollout.fall_step` itself."""
    def fallen(data: mujoco.MjData) -> bool:
        return bool(fall_step(_track(data), height_m, tilt_rad)[0] < 1)
    return fallen


def moved(poses: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """``poses[k, 3]`` with their position moved by ``offset`` (x, y; in each pose's frame)."""
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    return np.stack([poses[:, 0] + c * offset[0] - s * offset[1],
                     poses[:, 1] + s * offset[0] + c * offset[1], poses[:, 2]], axis=1)


def soles(data: mujoco.MjData, sites: tuple[str, str]) -> np.ndarray:
    """(x, y, heading) of two sole sites: their midpoint and mean x-axis direction."""
    a, b = data.site(sites[0]), data.site(sites[1])
    ax = a.xmat.reshape(3, 3)[:2, 0] + b.xmat.reshape(3, 3)[:2, 0]
    mid = 0.5 * (a.xpos[:2] + b.xpos[:2])
    return np.array([mid[0], mid[1], math.atan2(ax[1], ax[0])])
