"""A walk controller driven live: the command changes while the robot walks, and pushes come
when the user asks (the studio's keyboard / joystick view; issue 35).

The controller of a run folder (``policy.json`` + ``policy.npz``, as
:class:`~evomotion.sim.policy_player.PolicyPlayer` plays it) walks the robot from its nominal
stance; :meth:`LiveWalk.advance` runs whole control periods under the current command (the
player ramps it as training did), :meth:`LiveWalk.push` gives the torso an impulse at the next
physics step as the perturbed worlds do (the force ``impulse / dt`` on the torso during one
step: ``sim/worlds.py``). A fall is detected with the robot's own thresholds and stops the
walk until :meth:`LiveWalk.reset`.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from evomotion.core.checks import check_number
from evomotion.sim.policy_player import PolicyPlayer
from evomotion.sim.robots import load_robot
from evomotion.sim.state import STATE_SPEC
from evomotion.sim.walk_to_pose import fallen_test, torso_pose

CONTACTS = {"left": "left_floor", "right": "right_floor"}
MAX_PUSH_NS = 20.0
MAX_ADVANCE_S = 1.0


class LiveWalk:
    """The controller of run folder ``folder`` walking ``robot`` (a bundled name or a spec
    path: the run's ``problem.robot``; ``""`` the NAO) under a live command."""

    def __init__(self, folder: str | Path, robot: str = "nao") -> None:
        self.robot = load_robot(robot or "nao")
        self.model = m = self.robot.model
        self.player = PolicyPlayer(folder, m, CONTACTS)
        self.command_ranges = dict(self.player.command_ranges)
        self.data = mujoco.MjData(m)
        self.fallen = fallen_test(self.robot.fall_height_m, self.robot.fall_tilt_rad)
        free = np.flatnonzero(m.jnt_type == mujoco.mjtJoint.mjJNT_FREE)
        self.torso = int(m.jnt_bodyid[free[0]])
        self.mass_kg = float(m.body_subtreemass[self.torso])
        self.reset()

    def reset(self) -> None:
        """The robot standing in its nominal stance, the clock at 0, no command."""
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        mujoco.mj_setState(m, d, self.robot.state_at(self.player.nominal), STATE_SPEC)
        mujoco.mj_forward(m, d)
        self.player.start(d)
        self.fell = False
        self._push: np.ndarray | None = None
        self.start = torso_pose(d)
        #: the torso's height at the start (m): how big the robot is (a view frames it by it)
        self.height_m = float(d.xpos[self.torso][2])

    def push(self, impulse_ns: float, direction_deg: float) -> None:
        """An impulse (N s) on the torso in the horizontal direction ``direction_deg`` (world
        frame, 0 = +x), given during the next physics step."""
        check_number("push (N s)", impulse_ns, lo=0.0, hi=MAX_PUSH_NS)
        check_number("push direction (deg)", direction_deg, lo=-360.0, hi=360.0)
        a = math.radians(direction_deg)
        self._push = impulse_ns * np.array([math.cos(a), math.sin(a), 0.0])

    def advance(self, command: Any, seconds: float) -> int:
        """Run whole control periods for about ``seconds`` under ``command`` (clipped to the
        controller's ranges); the number run (0 once fallen)."""
        check_number("seconds", seconds, lo=0.0, hi=MAX_ADVANCE_S)
        if self.fell:
            return 0
        m, d, p = self.model, self.data, self.player
        lo = np.array([r[0] for r in self.command_ranges.values()])
        hi = np.array([r[1] for r in self.command_ranges.values()])
        cmd = np.clip(np.asarray(command, float).reshape(lo.size), lo, hi)
        periods = max(1, round(seconds / p.control_dt))
        for _ in range(periods):
            d.ctrl[:] = p.targets(d, cmd)
            for _ in range(p.control_steps):
                if self._push is not None:
                    d.xfrc_applied[self.torso, :3] = self._push / m.opt.timestep
                mujoco.mj_step(m, d)
                if self._push is not None:
                    d.xfrc_applied[self.torso, :3] = 0.0
                    self._push = None
            if not np.all(np.isfinite(d.qpos)) or self.fallen(d):
                self.fell = True
                return periods
        return periods

    def status(self) -> dict[str, float | bool]:
        """Time, the torso's pose relative to the start, its velocity in its own frame, the
        command the controller follows now, and whether the robot fell."""
        d = self.data
        x, y, th = torso_pose(d)
        c, s = math.cos(th), math.sin(th)
        v = d.qvel[:3]
        out: dict[str, float | bool] = {
            "t_s": float(d.time), "x_m": float(x - self.start[0]),
            "y_m": float(y - self.start[1]), "heading_deg": math.degrees(th - self.start[2]),
            "vx_m_s": float(c * v[0] + s * v[1]), "vy_m_s": float(-s * v[0] + c * v[1]),
            "yaw_rate_rad_s": float(d.qvel[5]), "fell": self.fell}
        for name, value in zip(self.command_ranges, self.player.command, strict=True):
            out[f"command_{name}"] = float(value)
        return out
