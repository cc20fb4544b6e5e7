"""Walking to the kick's stand pose with a closed-loop walk controller, in the kick's own
simulation (issue 34: ``play --walk`` with a ``humanoid-walk`` run).

The controller is the run's exported ``policy.npz`` + ``policy.json``, played by
:class:`evomotion.sim.policy_player.PolicyPlayer` in the kick scene (NAO + ball; foot contacts
from the scene's sole contact sensors) and walked by :class:`evomotion.sim.walk_to_pose.Walker`
(go-to-pose commands every 20 ms, closed loop on the torso pose; it stops with both feet down
where the crouch at the stand pose has them). Around the walk: from the crouch to the walk's
nominal stance over ``STANCE_S``; after it, to the crouch over ``CROUCH_S`` and a ``SETTLE_S``
rest before the kick. The torso waypoints are the Bézier approach's (the robot comes in behind
the ball along the kick line), moved to the walk stance's torso over the same feet
(:func:`.walk_play.ready_offset`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from evomotion.sim.policy_player import PolicyPlayer
from evomotion.sim.robots import nao
from evomotion.sim.walk_to_pose import (
    Walker,
    command_limits,
    fallen_test,
    moved,
    soles,
    torso_pose,
    wrap,
)

CONTACTS = {"left": "l_contact", "right": "r_contact"}
SOLES = ("l_sole_site", "r_sole_site")
STANCE_S, CROUCH_S, SETTLE_S = 0.4, 0.5, 0.5


def walk_controller(run: Any, folder: Path, goal: np.ndarray, path: np.ndarray | None = None,
                    tol_m: float = 0.005, tol_deg: float = 1.0,
                    max_s: float = 20.0) -> dict[str, Any]:
    """Walk the :class:`.walk_play.SceneRun` ``run`` to the crouch stand pose ``goal`` with the
    controller of ``folder``, through the waypoints of the Bézier ``path`` (its control points)
    when given; returns the time walked, whether the feet were reached and the final error of
    the feet (after the crouch and rest)."""
    from evomotion.studies.biped_kick.walk_play import ready_offset, waypoints

    p = run.problem
    m = p.model
    player = PolicyPlayer(folder, m, CONTACTS)
    vmax = command_limits(player, str(Path(folder) / "policy.json"))
    goals = waypoints(path, goal) if path is not None else np.asarray(goal, float)[None]
    goals = moved(goals, ready_offset(m, player.nominal))  # the walk stance's torso
    feet_goal = moved(np.asarray(goal, float)[None], -_crouch_torso_over_feet(m))[0]
    d = mujoco.MjData(m)
    mujoco.mj_setState(m, d, run.state, nao.STATE_SPEC)
    mujoco.mj_forward(m, d)
    w = Walker(m, d, player, torso_pose, lambda data: soles(data, SOLES),
               [int(m.sensor(s).adr[0]) for s in CONTACTS.values()],
               fallen_test(p.cfg.fall_height_m, p.cfg.fall_tilt_rad))
    w.ramp(nao.pose_vector(), player.nominal, STANCE_S)
    walked, reached = w.walk(goals, feet_goal, vmax, tol_m, tol_deg, max_s)
    w.ramp(d.ctrl.copy(), nao.pose_vector(), CROUCH_S)
    w.hold(nao.pose_vector(), round(SETTLE_S / m.opt.timestep))
    run.qpos.append(np.array(w.frames))
    run.time_s += len(w.frames) * m.opt.timestep
    run.state = nao.get_state(m, d)
    run.fell |= w.fallen(d)
    feet = soles(d, SOLES)
    return {"walk_s": walked, "reached": reached,
            "position_error_m": float(np.hypot(*(feet[:2] - feet_goal[:2]))),
            "heading_error_deg": float(math.degrees(abs(wrap(feet[2] - feet_goal[2])))),
            "pose": [float(v) for v in run.pose()]}


def _crouch_torso_over_feet(model: mujoco.MjModel) -> np.ndarray:
    """The crouch torso's position (x, y) over its soles' midpoint, in the robot's frame."""
    d = nao.initial_data(model)
    mujoco.mj_kinematics(model, d)
    return d.body("torso").xpos[:2] - soles(d, SOLES)[:2]
