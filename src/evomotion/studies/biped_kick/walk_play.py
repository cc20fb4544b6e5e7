"""Walking to the kick's stand pose with a NAO step repertoire, in the kick's own simulation.

The repertoire (``humanoid-repertoire`` run folder, format :mod:`evomotion.sim.repertoire`)
holds steps from the ready pose to the ready pose, each with its measured (dx, dy, dtheta). The
robot first goes from its crouch to the ready pose (``ready.motion``), then walks **closed
loop**: before every step it reads its torso pose from the simulation and plays the step whose
measured displacement brings it closest to the next waypoint (cost = position error + 0.01 m
per degree of heading error + 0.05 m per unit of the step's tilt objective, so calm steps are
preferred, as the repertoire's own ``walk-to`` prices them), holding the ready pose
``settle_s`` (1 s) after each step (the steps were measured from rest).

Waypoints are every ``spacing_m`` along the Bézier approach (heading = the path's tangent), so
the robot comes in behind the ball along the kick line instead of walking through it; the last
waypoint is the stand pose, reached within ``tol_m`` / ``tol_deg`` or when no step gets closer.
The walk aims at the ready-pose torso that stands over the same feet as the crouch at the stand
pose; then ``ready.motion`` backwards returns to the crouch the kick starts from. The Bézier
approach does not go around the ball: the robot should start on the kick side of it (``play``
refuses a start within 0.3 m of the ball).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.errors import InputError
from evomotion.run.config import run_of_study
from evomotion.sim.motion import Motion
from evomotion.sim.repertoire import read_cell, read_index, stepper_of
from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.replay import motion_targets
from evomotion.sim.rollout import fall_step, torso_track
from evomotion.studies.biped_kick.planning import bezier, wrap

HEADING_M_PER_DEG = 0.01
REPERTOIRE_STUDY = "humanoid-repertoire"
RISK_M = 0.05  # metres of pose error a step's tilt costs per unit of its (negative) objective


@dataclass
class SceneRun:
    """One continuing simulation of the kick scene: motions are played one after another
    from the last full physics state; the trajectory is kept for the video."""

    problem: Any
    state: np.ndarray
    qpos: list[np.ndarray] = field(default_factory=list)
    fell: bool = False
    time_s: float = 0.0

    def play(self, ctrl: np.ndarray) -> np.ndarray:
        """Play targets ``ctrl[n, 22]`` (one per physics step); returns the states."""
        p = self.problem
        states = p.sim.run(self.state, ctrl[None])
        self.state = states[0, -1]
        self.qpos.append(nao.state_qpos_all(p.model, states[0]))
        self.time_s += len(ctrl) * p.dt
        f = fall_step(torso_track(states), p.cfg.fall_height_m, p.cfg.fall_tilt_rad)[0]
        self.fell |= bool(f < len(ctrl))
        return states[0]

    def play_motion(self, motion: Motion, hold_s: float = 0.0) -> None:
        nstep = int(math.ceil((motion.duration_s + hold_s) / self.problem.dt))
        self.play(motion_targets(motion, self.problem.dt, nstep)[1])

    def pose(self) -> np.ndarray:
        """Torso (x, y, heading rad) now."""
        t = torso_track(self.state[None, None])
        return np.array([t.xyz[0, 0, 0], t.xyz[0, 0, 1], t.yaw_rad[0, 0]])


def waypoints(ctrl: np.ndarray, goal: np.ndarray, spacing_m: float = 0.15) -> np.ndarray:
    """Poses ``[k, 3]`` every ``spacing_m`` along the Bézier ``ctrl`` (heading = tangent),
    ending with ``goal`` (x, y, heading)."""
    t = np.linspace(0.0, 1.0, 400)
    pts = bezier(ctrl, t)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    marks = np.arange(spacing_m, s[-1] - 0.5 * spacing_m, spacing_m)
    idx = np.searchsorted(s, marks)
    out = []
    for i in idx:
        d = pts[min(i + 1, len(pts) - 1)] - pts[max(i - 1, 0)]
        out.append([pts[i, 0], pts[i, 1], math.atan2(d[1], d[0])])
    out.append(list(goal))
    return np.array(out)


def walk(run: SceneRun, repertoire: Path, ctrl: np.ndarray, goal: np.ndarray,
         tol_m: float = 0.015, tol_deg: float = 4.0, settle_s: float = 1.0,
         max_steps: int = 80) -> dict[str, Any]:
    """Walk ``run`` to ``goal`` (x, y, heading) along the Bézier ``ctrl`` with the steps of
    ``repertoire``; returns the steps taken and the final error."""
    folder, index = load_index(repertoire)
    if stepper_of(index) != "closed_form":
        raise InputError(f"{folder}: a repertoire of robot {index.get('robot')!r} evolved with "
                         "the numerical step; the kick walks the NAO with its closed-form step "
                         "(a humanoid-repertoire run without problem.robot)")
    entries = index["entries"]
    for name in ["ready.motion"] + [Path(str(e["file"])).name for e in entries]:
        if not (folder / name).is_file():
            raise InputError(f"{folder / name}: no such file (listed in the repertoire's "
                             "index, or its ready.motion)")
    steps = np.array([[e["measured"]["dx_m"], e["measured"]["dy_m"],
                       math.radians(e["measured"]["dtheta_deg"])] for e in entries])
    risk = RISK_M * np.maximum(-np.array([e["objective"] for e in entries], dtype=float), 0.0)
    cells: dict[int, Motion] = {}
    ready = read_cell(folder, {"file": "ready.motion"})
    run.play_motion(ready, hold_s=settle_s)
    # the steps move the torso of the ready pose, the kick starts from the crouch: aim the
    # walk at the ready-pose torso that stands over the same feet as the crouch at ``goal``
    shift = ready_offset(run.problem.model, ready.values[-1])
    c, s = math.cos(goal[2]), math.sin(goal[2])
    goal = np.array([goal[0] + c * shift[0] - s * shift[1], goal[1] + s * shift[0]
                     + c * shift[1], goal[2]])
    goals = waypoints(ctrl, goal)
    k = 0
    taken: list[int] = []
    while len(taken) < max_steps and not run.fell:
        pose = run.pose()
        last = k == len(goals) - 1

        def cost(p: np.ndarray, g: np.ndarray = goals[k]) -> np.ndarray:
            return (np.hypot(g[0] - p[..., 0], g[1] - p[..., 1])
                    + HEADING_M_PER_DEG * np.degrees(np.abs(wrap(g[2] - p[..., 2]))))

        now = float(cost(pose))
        close = (math.hypot(*(goals[k][:2] - pose[:2])) < (tol_m if last else 0.08)
                 and abs(math.degrees(wrap(goals[k][2] - pose[2]))) < (tol_deg if last
                                                                           else 20.0))
        if close and not last:
            k += 1
            continue
        c, s = math.cos(pose[2]), math.sin(pose[2])
        after = np.stack([pose[0] + c * steps[:, 0] - s * steps[:, 1],
                          pose[1] + s * steps[:, 0] + c * steps[:, 1], pose[2] + steps[:, 2]],
                         axis=1)
        costs = cost(after)
        j = int(np.argmin(costs + risk))
        if close or costs[j] >= now:
            if last:
                break
            k += 1
            continue
        if j not in cells:
            cells[j] = read_cell(folder, entries[j])
        run.play_motion(cells[j], hold_s=settle_s)
        taken.append(int(entries[j].get("cell", j)))
    back = Motion(ready.joints, ready.times_ms[-1] - ready.times_ms[::-1],
                  ready.values[::-1].copy())
    run.play_motion(back, hold_s=0.5)
    pose = run.pose()
    return {"steps": len(taken), "cells": taken,
            "position_error_m": float(math.hypot(*(goal[:2] - pose[:2]))),
            "heading_error_deg": float(math.degrees(abs(wrap(goal[2] - pose[2])))),
            "pose": [float(v) for v in pose]}


def ready_offset(model: Any, ready_pose: np.ndarray) -> np.ndarray:
    """Torso position (x, y; m, in the robot's heading frame) of the ready pose minus that of
    the crouch when both stand over the same feet (the midpoint of the soles)."""
    import mujoco

    mid = []
    for pose in (None, ready_pose):
        d = nao.initial_data(model, pose)
        mujoco.mj_kinematics(model, d)
        feet = 0.5 * (d.site("l_sole_site").xpos[:2] + d.site("r_sole_site").xpos[:2])
        mid.append(d.body("torso").xpos[:2] - feet)
    return mid[1] - mid[0]


def load_index(repertoire: Path, option: str = "--walk") -> tuple[Path, dict]:
    """``(folder, index)`` of the repertoire run ``repertoire`` (a humanoid-repertoire run
    folder or its ``repertoire/``, checked by its config.toml; the index bounded and checked
    field by field)."""
    return read_index(run_of_study(repertoire, REPERTOIRE_STUDY, option, "repertoire"))

