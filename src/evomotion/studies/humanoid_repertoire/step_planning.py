"""Using a repertoire: ``pick`` the step nearest a requested one, ``walk-to`` a target pose.

``pick``: the filled cell whose *measured* (dx, dy, dtheta) is nearest the request, distances
normalised by each measure's archive range.

``walk-to``: a best-first (A*) search over sequences of repertoire steps. A state is the
planar pose (x, y, theta) after some steps; a step moves it by its measured displacement,
rotated by the current heading. A step costs ``1 + risk_weight * (-objective)`` (1 to about 2:
a step that tilts the torso more costs more, so plans prefer the stable steps); the
heuristic is ``max(distance / longest step, |heading error| / largest turn)`` (admissible: no
step moves farther or turns more, and none costs less than 1), weighted by ``greed`` (2:
weighted A*, a plan at most twice the cheapest, found in far fewer expansions); the search
stops at the
first pose within ``tol_m`` and ``tol_deg`` of the target (or at the pose closest to it
when ``max_expansions`` run out).
Poses are merged on a 1 cm / 2 degree lattice. The chained motion (``ready.motion`` is not
included: the steps start and end in the ready pose) holds the ready pose ``settle_s`` (1 s)
between steps, so each step starts from rest as when it was measured, and is then played in
simulation.
"""

from __future__ import annotations

import heapq
import math
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.core.checks import check_number
from evomotion.errors import InputError
from evomotion.sim.repertoire import chain, read_cell, stepper_of
from evomotion.studies.humanoid_repertoire.runfiles import load_index

#: the farthest request or target (m, each of x and y) and the largest turn (degrees)
MAX_TARGET_M = 10.0
MAX_TARGET_DEG = 360.0


def check_request(names: tuple[str, str, str], x: float, y: float, theta_deg: float) -> None:
    """One-line error unless (x, y, theta) are finite and within the documented ranges."""
    for name, v, lim in zip(names, (x, y, theta_deg),
                            (MAX_TARGET_M, MAX_TARGET_M, MAX_TARGET_DEG), strict=True):
        check_number(name, v, lo=-lim, hi=lim)


def _measures(index: dict) -> tuple[np.ndarray, list[dict]]:
    entries = index["entries"]
    return np.array([[e["measured"]["dx_m"], e["measured"]["dy_m"],
                      e["measured"]["dtheta_deg"]] for e in entries], float), entries


def pick(run: Path, dx: float, dy: float, dtheta_deg: float) -> dict:
    """The nearest filled cell to the request: ``{file, cell, measured, objective,
    distance}`` (``file`` absolute)."""
    check_request(("--dx", "--dy", "--dtheta"), dx, dy, dtheta_deg)
    folder, index = load_index(run)
    m, entries = _measures(index)
    scale = _box_size(index)
    d = np.linalg.norm((m - [dx, dy, dtheta_deg]) / scale, axis=1)
    i = int(np.argmin(d))
    e = entries[i]
    read_cell(folder, e, _cell_joints(_robot_problem(folder, index)))  # it is a motion
    return {"file": str((folder / Path(e["file"]).name).resolve()), "cell": e["cell"],
            "measured": e["measured"], "objective": e["objective"],
            "requested": {"dx_m": dx, "dy_m": dy, "dtheta_deg": dtheta_deg},
            "normalised_distance": float(d[i])}


#: the NAO archive's ranges (m, m, deg): problem.MEASURES, for indexes without a box
NAO_BOX_SIZE = (0.25, 0.16, 90.0)


def _box_size(index: dict) -> np.ndarray:
    """The archive's ranges (m, m, deg): from the index's ``box``, else the NAO's."""
    box: Any = index.get("box")  # the file's: anything (a wrong one is refused below)
    try:
        size = np.array(box["upper"], float) - np.array(box["lower"], float)
    except (TypeError, KeyError, ValueError):
        size = None
    ok = size is not None and size.shape == (3,) and np.all(np.isfinite(size) & (size > 0))
    return size if ok else np.array(NAO_BOX_SIZE)


def _compose(pose: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """The poses ``[n, 3]`` after each of ``steps[n, 3]`` from ``pose`` (x, y, theta deg)."""
    x, y, th = pose
    c, s = math.cos(math.radians(th)), math.sin(math.radians(th))
    return np.stack([x + c * steps[:, 0] - s * steps[:, 1], y + s * steps[:, 0]
                     + c * steps[:, 1], th + steps[:, 2]], axis=1)


#: successors pushed by one plan at most (about a second of search): the expansions are
#: cut to ``MAX_PUSHES / len(steps)`` for a large repertoire
MAX_PUSHES = 1_000_000


def plan(steps: np.ndarray, target: np.ndarray, tol_m: float = 0.03, tol_deg: float = 5.0,
         max_steps: int = 60, max_expansions: int = 20_000,
         objective: np.ndarray | None = None,
         risk_weight: float = 1.0, greed: float = 2.0) -> tuple[list[int], np.ndarray]:
    """Indices of repertoire ``steps[n, 3]`` (dx m, dy m, dtheta deg) to reach ``target`` (x,
    y, theta deg) from the origin, and the planned final pose (A*, see the module doc)."""
    steps = np.asarray(steps, dtype=float).reshape(-1, 3)
    target = np.asarray(target, dtype=float)
    if not len(steps) or not (np.all(np.isfinite(steps)) and np.all(np.isfinite(target))):
        raise InputError("walk-to: expected a repertoire of finite steps and a finite target")
    reach = max(float(np.hypot(steps[:, 0], steps[:, 1]).max()), 1e-3)
    turn = max(float(np.abs(steps[:, 2]).max()), 1e-3)

    def err(p):
        p = np.asarray(p)
        return (np.hypot(p[..., 0] - target[0], p[..., 1] - target[1]),
                np.abs((p[..., 2] - target[2] + 180) % 360 - 180))

    def h(p):
        dist, ang = err(p)
        return np.maximum(dist / reach, ang / turn)

    cost = 1.0 + risk_weight * np.maximum(-np.asarray(objective, float), 0.0) \
        if objective is not None else np.ones(len(steps))
    start = np.zeros(3)
    heap: list[tuple[float, float, int, np.ndarray, tuple[int, ...]]] = [
        (float(h(start)), 0.0, 0, start, ())]
    seen: set[tuple[int, int, int]] = set()
    best: tuple[float, np.ndarray, tuple[int, ...]] = (math.inf, start, ())
    tie = 0
    for _ in range(min(max_expansions, max(1, MAX_PUSHES // len(steps)))):
        if not heap:
            break
        _, g, _, p, path = heapq.heappop(heap)
        dist, ang = (float(v) for v in err(p))
        score = dist + 0.01 * ang
        if score < best[0]:
            best = (score, p, path)
        if dist <= tol_m and ang <= tol_deg:
            return list(path), p
        key = (round(p[0] / 0.01), round(p[1] / 0.01), round(p[2] / 2.0))
        if key in seen or len(path) >= max_steps:
            continue
        seen.add(key)
        q = _compose(p, steps)
        gq = g + cost
        fq = (gq + greed * h(q)).tolist()
        gq = gq.tolist()
        for i in range(len(steps)):
            tie += 1
            heapq.heappush(heap, (fq[i], gq[i], tie, q[i], path + (i,)))
    return list(best[2]), best[1]


def with_pauses(motions: list, settle_s: float) -> list:
    """Each motion followed by its last pose held ``settle_s`` (the last one not)."""
    from evomotion.sim.motion import Motion

    if settle_s <= 0:
        return motions
    ms = int(round(settle_s * 1000 / 20)) * 20
    out = []
    for i, m in enumerate(motions):
        if i < len(motions) - 1:
            t = np.r_[m.times_ms, m.times_ms[-1] + ms]
            m = Motion(m.joints, t, np.vstack([m.values, m.values[-1:]]))
        out.append(m)
    return out


def walk_to(run: Path, x: float, y: float, theta_deg: float, video: Path | None = None,
            out: Path | None = None, hold_s: float = 2.0, settle_s: float = 1.0) -> dict:
    """Plan, chain, play in simulation; the chained motion goes to ``out`` (default: in the
    run folder). Every path is checked before the work starts."""
    from evomotion.outfile import atomic_write_text, check_target
    from evomotion.sim.motion import format_motion
    from evomotion.sim.robots.nao.replay import replay_motion

    check_request(("--x", "--y", "--theta"), x, y, theta_deg)
    target = np.array([x, y, theta_deg], float)
    check_number("hold (s)", hold_s, lo=0.0, hi=60.0)
    check_number("settle (s)", settle_s, lo=0.0, hi=60.0)
    folder, index = load_index(run)
    run = folder.parent
    if video is not None:
        if Path(video).suffix.lower() != ".mp4":
            raise InputError(f"--video {video}: expected a .mp4 path")
        video = check_target(video, "video (--video)")
    out = Path(out) if out is not None else \
        run / f"walk_to_{x:+.2f}_{y:+.2f}_{theta_deg:+.0f}.motion"
    out = check_target(out, "chained motion (--out)")
    m, entries = _measures(index)
    idx, planned = plan(m, target, objective=np.array([e["objective"] for e in entries]))
    if not idx:
        raise InputError("walk-to: the target is the start pose (nothing to do) or no "
                         "step of the repertoire gets closer to it")
    problem = _robot_problem(folder, index)
    joints = _cell_joints(problem)
    motion = chain(with_pauses([read_cell(folder, entries[i], joints) for i in idx], settle_s))
    atomic_write_text(out, format_motion(motion), "chained motion (--out)")
    if problem is None:
        summary, skipped = replay_motion(motion, video, hold_s)
    else:
        summary, skipped = _play_on_robot(problem.robot, motion, video, hold_s)
    dx, dy = summary["displacement_m"]
    th = math.degrees(summary["heading_change_rad"])
    return {"target": {"x_m": x, "y_m": y, "theta_deg": theta_deg},
            "steps": len(idx), "cells": [entries[i]["cell"] for i in idx],
            "planned": {"x_m": float(planned[0]), "y_m": float(planned[1]),
                        "theta_deg": float(planned[2])},
            "reached": {"x_m": dx, "y_m": dy, "theta_deg": th},
            "position_error_m": float(math.hypot(dx - x, dy - y)),
            "heading_error_deg": float(abs((th - theta_deg + 180) % 360 - 180)),
            "fell": bool(summary["fell"]), "motion": str(out),
            "duration_s": motion.duration_s,
            "video": str(video) if video is not None and skipped is None else None}


def _robot_problem(folder: Path, index: dict):
    """The problem of the run whose repertoire is ``folder`` (its run folder holds it); None
    for the NAO's closed-form steps (``index``'s stepper), which need none."""
    from evomotion.studies.humanoid_repertoire.artifacts import run_problem

    if stepper_of(index) == "closed_form":
        return None
    run = folder.parent
    problem = run_problem(run)
    if problem is None:
        raise InputError(f"{run}: the repertoire is another robot's than the NAO, but the "
                         "run's config.toml has no problem.robot")
    return problem


def _cell_joints(problem) -> tuple[str, ...] | None:
    """The channels of the repertoire's .motion files: the robot's, None for the NAO's."""
    return None if problem is None else problem.robot.joints


def _play_on_robot(robot, motion, video: Path | None, hold_s: float
                   ) -> tuple[dict, str | None]:
    """Play ``motion`` on ``robot``, with a video when one is named."""
    from evomotion.sim.play import play_motion, robot_camera
    from evomotion.sim.render import RenderUnavailableError, render_video

    result = play_motion(robot, motion, hold_s)
    skipped = None
    if video is not None:
        try:
            if not robot.xml:
                raise RenderUnavailableError("the robot's model cannot be written as MJCF")
            render_video(result["qpos"], result["dt"], video, model_xml=robot.xml,
                         camera=robot_camera(robot))
        except RenderUnavailableError as exc:
            skipped = str(exc)
    return result["summary"], skipped
