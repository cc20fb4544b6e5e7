"""Run-folder artifacts of ``humanoid-repertoire``.

- ``repertoire/cell-NNNN.motion``: the elite step of every filled cell (ready pose to ready
  pose, so they chain; another robot's: its channels), ``repertoire/ready.motion`` (the NAO's
  initial crouch to the ready pose: play it first; another robot starts in its ready pose),
  ``repertoire/index.json``: the robot, the measure box, per cell its file, measured
  dx/dy/dtheta, objective, the cell's centre and the genes by name;
- ``repertoire/contact_sheet.mp4``: six standing cells spread over the archive, each
  replayed on its own from the ready pose, one after the other;
- ``archive.npz`` and ``plots/archive.png`` (the heat map) come from the run loop.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.run.context import RunContext
from evomotion.run.folder import atomic_write_text
from evomotion.sim import nao
from evomotion.sim.nao.motion import Motion, format_motion
from evomotion.sim.nao.repertoire import INDEX, chain, read_cell, read_index  # noqa: F401
from evomotion.studies.humanoid_repertoire import step

READY_S = 0.6


def ready_motion() -> Motion:
    """From the NAO's initial pose to the ready pose in ``READY_S`` (joint space)."""
    t = np.arange(0, int(READY_S * 1000) + 1, step.POSE_MS, dtype=np.int64)
    x = np.clip(t / t[-1], 0, 1)[:, None]
    s = x * x * (3 - 2 * x)
    q = nao.pose_vector()[None] + s * (step.ready_pose() - nao.pose_vector())[None]
    return Motion(nao.JOINTS, t, q)


def best_record(ctx: RunContext) -> dict[str, Any]:
    if ctx.best_genome is None or not np.all(np.isfinite(ctx.best_genome)):
        return {}
    return {"step": step.named(ctx.best_genome)}


def write_repertoire(out_dir: Path, hold_s: float, problem: Any = None) -> list[dict]:
    """``repertoire/`` from the run's ``archive.npz``: the cells whose elite stays up and
    whose measured behaviour lies inside the archive's box (a grid puts behaviour outside it
    in its edge cells: those are archived, not exported); returns the index entries.
    ``problem``: the run's problem (its ``motion`` and ``measure_spec``; another robot's
    steps are motions of its channels); None: the NAO's."""
    from evomotion.run.archive_file import read_archive
    from evomotion.studies.humanoid_repertoire.problem import FALLEN_OBJECTIVE, MEASURES

    robot = None if getattr(problem, "is_nao", True) else problem.robot
    box = MEASURES if robot is None else problem.measure_spec
    motion_of = step_motion if robot is None else problem.motion
    a = read_archive(out_dir / "archive.npz")
    folder = out_dir / "repertoire"
    folder.mkdir(exist_ok=True)
    for old in folder.glob("cell-*.motion"):  # cells change as the archive improves
        old.unlink()
    inside = np.all((a.measures >= box.lower) & (a.measures <= box.upper), axis=1)
    up = a.objective > FALLEN_OBJECTIVE + 1.0
    entries = []
    for k in np.flatnonzero(inside & up):
        c = int(a.cell[k])
        name = f"cell-{c:04d}.motion"
        atomic_write_text(folder / name, format_motion(motion_of(a.solution[k])))
        entries.append({"cell": c, "file": name,
                        "measured": {n: float(v) for n, v in zip(a.measure_names,
                                                                 a.measures[k], strict=True)},
                        "objective": float(a.objective[k]),
                        "centre": [float(v) for v in a.centre[k]],
                        "genes": step.named(a.solution[k])})
    if robot is None:
        atomic_write_text(folder / "ready.motion", format_motion(ready_motion()))
    atomic_write_text(folder / INDEX, json.dumps({
        "robot": "nao" if robot is None else robot.name,
        "is_nao": robot is None,  # the NAO's own step (a copy of nao.toml is another robot)
        "box": {"lower": box.lower.tolist(), "upper": box.upper.tolist()},
        "measures": list(a.measure_names), "cells": a.cells, "archived": int(a.cell.size),
        "fallen": int((~up).sum()), "outside_box": int((up & ~inside).sum()),
        "hold_s": hold_s, "entries": entries}, indent=1) + "\n")
    return entries


def step_motion(genes: np.ndarray) -> Motion:
    """The NAO step of one genome (ready pose to ready pose) as a Webots motion."""
    q = step.poses(genes)
    return Motion(nao.JOINTS, np.arange(len(q), dtype=np.int64) * step.POSE_MS, q)


def run_problem(run: Path) -> Any:
    """The problem of a run folder (from its config.toml) when it is another robot's than
    the NAO, else None (the NAO's steps need no problem to be rebuilt)."""
    from evomotion.run.config import config_from_dict, config_from_run_dir
    from evomotion.sim.robot import is_nao
    from evomotion.studies import get_study

    name, raw = config_from_run_dir(run)
    problem = raw.get("problem")
    robot = problem.get("robot", "") if isinstance(problem, dict) else ""
    if not isinstance(robot, str) or is_nao(robot):
        return None
    study = get_study(name)
    return study.make_problem(config_from_dict(study, raw).problem)


def on_checkpoint(ctx: RunContext) -> None:
    if (ctx.out_dir / "archive.npz").exists():
        write_repertoire(ctx.out_dir, ctx.problem.cfg.hold_s, ctx.problem)


def finalize(ctx: RunContext) -> None:
    if not (ctx.out_dir / "archive.npz").exists():
        return
    entries = write_repertoire(ctx.out_dir, ctx.problem.cfg.hold_s, ctx.problem)
    if not entries:
        ctx.log("repertoire: no standing step inside the archive's box yet")
        return
    ctx.log(f"repertoire: {len(entries)} standing steps -> repertoire/ (index.json, one "
            ".motion each)")
    sheet = spread(entries, 6)
    try:
        contact_sheet(ctx.out_dir / "repertoire", sheet,
                      ctx.out_dir / "repertoire" / "contact_sheet.mp4",
                      robot=None if ctx.problem.is_nao else ctx.problem.robot)
    except RuntimeError as exc:  # no GL backend (RenderUnavailableError) or a render error
        ctx.log(f"contact_sheet.mp4 skipped: {exc}")
        return
    ctx.log("repertoire/contact_sheet.mp4: cells " + ", ".join(str(e["cell"]) for e in sheet))


def contact_sheet(folder: Path, entries: list[dict], video: Path, hold_s: float = 1.0,
                  robot: Any = None) -> Path:
    """One video of the cells' steps, each replayed on its own from the ready pose (cut to
    the next one when its hold ends); ``robot``: another robot than the NAO."""
    from evomotion.sim.render import check_videos_on, render_video

    check_videos_on()
    if robot is None:
        from evomotion.sim.nao.replay import simulate_motion

        runs = [simulate_motion(read_cell(folder, e), hold_s=hold_s) for e in entries]
        return render_video(np.concatenate([r["qpos"] for r in runs]), runs[0]["dt"], video)
    from evomotion.sim.robot.play import play_motion, robot_camera

    if not robot.xml:
        raise RuntimeError("the robot's edited model cannot be written as MJCF text")
    runs = [play_motion(robot, read_cell(folder, e, robot.joints), hold_s=hold_s)
            for e in entries]
    return render_video(np.concatenate([r["qpos"] for r in runs]), runs[0]["dt"], video,
                        model_xml=robot.xml, camera=robot_camera(robot))


def spread(entries: list[dict], k: int) -> list[dict]:
    """``k`` entries far apart in measure space (farthest-point order from the best)."""
    m = np.array([list(e["measured"].values()) for e in entries])
    scale = np.maximum(m.max(0) - m.min(0), 1e-9)
    z = m / scale
    chosen = [int(np.argmax([e["objective"] for e in entries]))]
    d = np.linalg.norm(z - z[chosen[0]], axis=1)
    while len(chosen) < min(k, len(entries)):
        chosen.append(int(np.argmax(d)))
        d = np.minimum(d, np.linalg.norm(z - z[chosen[-1]], axis=1))
    return [entries[i] for i in chosen]
