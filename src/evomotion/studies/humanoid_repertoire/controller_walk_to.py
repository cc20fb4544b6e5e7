"""``walk-to`` with a closed-loop walk controller (issue 34): ``evomotion humanoid-repertoire
walk-to RUN`` where RUN is a ``humanoid-walk`` run walks the NAO to the target pose with the
run's exported controller instead of a chain of repertoire steps (which remains the command for
a humanoid-repertoire run). The robot is the run's (``problem.robot``: the NAO, or the OP3 of
``--robot op3``).

The robot starts standing at rest in the controller's nominal stance (the start of its training
episodes) at the origin facing +x; :class:`evomotion.sim.walk_to_pose.Walker` walks it (go-to-
pose commands every control period, closed loop on the torso pose) until both feet are down
within ``tol_m`` / ``tol_deg`` of where the target pose puts them (the target is the torso's,
the feet kept where they are under the torso at the start), or ``max_s``; then the controller
targets move to its nominal stance over ``STOP_S`` (it stops stepping; at a zero command
the controller steps in place and drifts several degrees in 2 s) and it stands for ``hold_s``;
then the result is measured: the torso's displacement and
heading change, as the repertoire's ``walk-to`` reports them. Nothing is written but the video.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from evomotion.sim.policy_player import PolicyPlayer
from evomotion.sim.robots import load_robot
from evomotion.sim.state import STATE_SPEC
from evomotion.sim.walk_to_pose import (
    Walker,
    command_limits,
    fallen_test,
    moved,
    soles,
    torso_pose,
    wrap,
)

CONTACTS = {"left": "left_floor", "right": "right_floor"}
STOP_S = 0.5  # from the last walking targets to the standing stance (s)


def run_robot(run: Path) -> str:
    """The robot of a humanoid-walk run folder (its config's ``problem.robot``; "" when
    it names none: the NAO)."""
    from evomotion.run.config import config_from_run_dir, configured_robot

    robot = configured_robot(config_from_run_dir(run)[1])
    return robot if isinstance(robot, str) else ""


def controller_walk_to(run: Path, x: float, y: float, theta_deg: float,
                       video: Path | None = None, hold_s: float = 2.0, tol_m: float = 0.02,
                       tol_deg: float = 3.0, max_s: float = 60.0) -> dict[str, Any]:
    """Walk to (x, y, theta_deg) with the controller of the humanoid-walk run ``run``, on
    the run's robot."""
    robot = load_robot(run_robot(Path(run)) or "nao")
    m = robot.model
    player = PolicyPlayer(run, m, CONTACTS)
    vmax = command_limits(player, str(Path(run) / "policy.json"))
    d = mujoco.MjData(m)
    sites = (robot.sole_site("left"), robot.sole_site("right"))
    mujoco.mj_setState(m, d, robot.state_at(player.nominal), STATE_SPEC)
    mujoco.mj_forward(m, d)
    start = torso_pose(d)
    under = soles(d, sites)[:2] - start[:2]  # feet under the torso (start heading is 0)
    goal = np.array([start[0] + x, start[1] + y, math.radians(theta_deg)])
    feet_goal = moved(goal[None], under)[0]
    w = Walker(m, d, player, torso_pose, lambda data: soles(data, sites),
               [int(m.sensor(s).adr[0]) for s in CONTACTS.values()],
               fallen_test(robot.fall_height_m, robot.fall_tilt_rad))
    walked, reached = w.walk(goal[None], feet_goal, vmax, tol_m, tol_deg, max_s)
    w.ramp(d.ctrl.copy(), player.nominal, STOP_S)  # stop stepping: stand in the stance
    w.hold(player.nominal, round(hold_s / m.opt.timestep))
    end = torso_pose(d)
    dx, dy = end[0] - start[0], end[1] - start[1]
    th = math.degrees(wrap(end[2] - start[2]))
    skipped = None
    if video is not None:
        from evomotion.sim.render import RenderUnavailableError, render_video

        try:
            render_video(np.array(w.frames), m.opt.timestep, video, robot=robot)
        except RenderUnavailableError as exc:
            skipped = str(exc)
    return {"target": {"x_m": x, "y_m": y, "theta_deg": theta_deg},
            "controller": str(run), "walk_s": walked, "feet_reached": reached,
            "reached": {"x_m": float(dx), "y_m": float(dy), "theta_deg": th},
            "position_error_m": float(math.hypot(dx - x, dy - y)),
            "heading_error_deg": float(abs((th - theta_deg + 180) % 360 - 180)),
            "fell": bool(w.fallen(d)), "duration_s": len(w.frames) * m.opt.timestep,
            "video": str(video) if video is not None and skipped is None else None,
            **({"video_skipped": skipped} if skipped else {})}
