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
import os
import re
import stat
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.outfile import WriteError, atomic_write_text, claim, kind_of, reason
from evomotion.run.context import RunContext
from evomotion.sim.motion import Motion, format_motion
from evomotion.sim.repertoire import INDEX, chain, read_cell, read_index  # noqa: F401
from evomotion.sim.robots import nao
from evomotion.studies.humanoid_repertoire import step

READY_S = 0.6


def ready_motion() -> Motion:
    """From the NAO's initial pose to the ready pose in ``READY_S`` (joint space)."""
    t = np.arange(0, int(READY_S * 1000) + 1, step.POSE_MS, dtype=np.int64)
    x = np.clip(t / t[-1], 0, 1)[:, None]
    s = x * x * (3 - 2 * x)
    q = nao.pose_vector()[None] + s * (step.ready_pose() - nao.pose_vector())[None]
    return Motion(nao.JOINTS, t, q)


def genome_motion(problem: Any, genome: np.ndarray) -> Motion:
    """One genome's step as the motion the archive's cells export (ready pose to ready pose;
    another robot's channels): the studio replays a generation's best with it."""
    return problem.motion(np.asarray(genome, dtype=float))


def best_record(ctx: RunContext) -> dict[str, Any]:
    if ctx.best_genome is None or not np.all(np.isfinite(ctx.best_genome)):
        return {}
    return {"step": step.named(ctx.best_genome)}


def write_repertoire(out_dir: Path, hold_s: float, problem: Any = None) -> list[dict]:
    """``repertoire/`` from the run's ``archive.npz``: the cells whose elite stays up and
    whose measured behaviour lies inside the archive's box (a grid puts behaviour outside it
    in its edge cells: those are archived, not exported); returns the index entries.
    ``problem``: the run's problem (its ``motion`` and ``measure_spec``; another robot's
    steps are motions of its channels); None: the NAO's.

    A function of the archive alone: the same archive gives the same files, byte for byte,
    however often it is called; cell files of an earlier archive that are no longer in it
    are removed (after the new index is written), so the folder holds exactly the files the
    index names (``ready.motion`` and ``contact_sheet.mp4`` besides)."""
    from evomotion.core.checks import check_number
    from evomotion.studies.humanoid_repertoire.problem import (
        FALLEN_OBJECTIVE,
        MAX_HOLD_S,
        MEASURES,
    )
    from evomotion.studies.humanoid_repertoire.runfiles import load_archive

    check_number("hold (s)", hold_s, lo=0.0, hi=MAX_HOLD_S)
    robot = None if problem is None or problem.steps.name == "closed_form" else problem.robot
    box = MEASURES if robot is None else problem.measure_spec
    motion_of = step_motion if robot is None else problem.motion
    a = load_archive(out_dir / "archive.npz")
    lower, upper = (step.LOWER, step.UPPER) if robot is None else \
        (problem.genome.lower, problem.genome.upper)
    check_solutions(out_dir / "archive.npz", a.solution, a.cell, lower, upper)
    folder = repertoire_folder(out_dir)
    inside = np.all((a.measures >= box.lower) & (a.measures <= box.upper), axis=1)
    up = a.objective > FALLEN_OBJECTIVE + 1.0
    entries: list[dict[str, Any]] = []
    for k in np.flatnonzero(inside & up):
        c = int(a.cell[k])
        name = f"cell-{c:04d}.motion"
        atomic_write_text(folder / name, format_motion(motion_of(a.solution[k])),
                          "repertoire step")
        entries.append({"cell": c, "file": name,
                        "measured": {n: float(v) for n, v in zip(a.measure_names,
                                                                 a.measures[k], strict=True)},
                        "objective": float(a.objective[k]),
                        "centre": [float(v) for v in a.centre[k]],
                        "genes": step.named(a.solution[k])})
    if robot is None:
        atomic_write_text(folder / "ready.motion", format_motion(ready_motion()),
                          "repertoire ready motion")
    atomic_write_text(folder / INDEX, json.dumps({
        "robot": "nao" if robot is None else robot.name,
        # the closed-form step of a robot with leg_ik (a copy of nao.toml is another robot)
        "stepper": "closed_form" if robot is None else "numerical",
        "box": {"lower": box.lower.tolist(), "upper": box.upper.tolist()},
        "measures": list(a.measure_names), "cells": a.cells, "archived": int(a.cell.size),
        "fallen": int((~up).sum()), "outside_box": int((up & ~inside).sum()),
        "hold_s": float(hold_s), "entries": entries}, indent=1, allow_nan=False) + "\n",
        "repertoire index")
    remove_stale_cells(folder, {e["file"] for e in entries})
    return entries


def check_solutions(path: Path, solution: np.ndarray, cell: np.ndarray, lower: np.ndarray,
                    upper: np.ndarray) -> None:
    """One-line :class:`InputError` unless every archived elite has the genome's number of
    genes, each inside its bounds (the search clips every genome into them; a tolerance of
    1e-9 of the range for rounding): an archive edited by hand exports nothing absurd."""
    from evomotion.errors import InputError

    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    if solution.ndim != 2 or solution.shape[1] != lower.size:
        raise InputError(f"{path}: 'solution' holds {solution.shape[-1]} genes per cell, "
                         f"expected {lower.size} (this run's genome)")
    tol = 1e-9 * (upper - lower)
    out = ~np.all((solution >= lower - tol) & (solution <= upper + tol), axis=1)
    if out.any():
        k = int(np.flatnonzero(out)[0])
        raise InputError(f"{path}: cell {int(cell[k])}'s genes lie outside the genome's "
                         f"bounds (an archive this run did not write)")


_CELL_FILE = re.compile(r"^cell-[0-9]+\.motion$")


def repertoire_folder(out_dir: Path) -> Path:
    """``out_dir/repertoire``, made if missing; a link or anything but a folder there is
    refused (the run's files are never written through a link out of the run folder)."""
    folder = out_dir / "repertoire"
    try:
        st = os.lstat(folder)
    except FileNotFoundError:
        try:
            folder.mkdir()
        except OSError as e:
            raise WriteError(f"{folder}: cannot make the repertoire folder ({reason(e)})"
                             ) from None
        claim(folder)  # a folder the run made: the run's (--overwrite removes it)
        return folder
    except OSError as e:
        raise WriteError(f"{folder}: cannot use the repertoire folder ({reason(e)})") from None
    if not stat.S_ISDIR(st.st_mode):
        raise WriteError(f"{folder}: expected the repertoire folder, found "
                         f"{'a link' if stat.S_ISLNK(st.st_mode) else kind_of(st.st_mode)}")
    return folder


def remove_stale_cells(folder: Path, keep: set[str]) -> list[str]:
    """Remove the cell files of ``folder`` (``cell-N.motion``: regular files or links, never
    what a link points at, never a folder) that ``keep`` does not name; their names."""
    removed = []
    for p in sorted(folder.iterdir()):
        if p.name in keep or not _CELL_FILE.match(p.name):
            continue
        st = os.lstat(p)
        if not (stat.S_ISREG(st.st_mode) or stat.S_ISLNK(st.st_mode)):
            continue
        try:
            p.unlink()
        except FileNotFoundError:
            continue
        except OSError as e:
            raise WriteError(f"{p}: cannot remove a step no longer in the archive "
                             f"({reason(e)})") from None
        removed.append(p.name)
    return removed


def step_motion(genes: np.ndarray) -> Motion:
    """The NAO step of one genome (ready pose to ready pose) as a Webots motion."""
    q = step.poses(genes)
    return Motion(nao.JOINTS, np.arange(len(q), dtype=np.int64) * step.POSE_MS, q)


def run_problem(run: Path, config: Any = None) -> Any:
    """The problem of a run folder (from its config.toml, or ``config``, its resolved
    :class:`~evomotion.run.config.Config`) when it is another robot's than the NAO, else
    None (the NAO's steps need no problem to be rebuilt)."""
    from evomotion.sim.robots import capabilities_of
    from evomotion.studies.humanoid_repertoire.problem import make_problem
    from evomotion.studies.humanoid_repertoire.runfiles import run_config
    from evomotion.studies.humanoid_repertoire.steppers import CLOSED_FORM_CAPABILITIES

    cfg = config if config is not None else run_config(run)
    if set(CLOSED_FORM_CAPABILITIES) <= set(capabilities_of(cfg.problem.robot)):
        return None
    return make_problem(cfg.problem)


def export(run: Path, hold_s: float | None = None) -> tuple[Path, list[dict]]:
    """``evomotion humanoid-repertoire export``: the run folder checked to be a repertoire
    run, its ``repertoire/`` rebuilt from ``archive.npz``; ``hold_s`` recorded in the index
    (default: the run's ``problem.hold_s``)."""
    from evomotion.core.checks import check_number
    from evomotion.studies.humanoid_repertoire.problem import MAX_HOLD_S
    from evomotion.studies.humanoid_repertoire.runfiles import repertoire_run, run_config

    if hold_s is not None:
        check_number("--hold", hold_s, lo=0.0, hi=MAX_HOLD_S)
    run = repertoire_run(run)
    cfg = run_config(run)
    hold = cfg.problem.hold_s if hold_s is None else hold_s
    return run, write_repertoire(run, hold, run_problem(run, cfg))


def _write(ctx: RunContext) -> list[dict]:
    """The repertoire of the run's archive, written once per generation (the finishing
    phase calls both hooks)."""
    out = ctx.out_dir
    assert out is not None  # the artifact hooks run only in a run with a folder
    key = ("humanoid-repertoire", ctx.generation, ctx.evaluations)
    if ctx.cache.get("repertoire-written") != key:
        ctx.cache["repertoire-entries"] = write_repertoire(out, ctx.problem.cfg.hold_s,
                                                           ctx.problem)
        ctx.cache["repertoire-written"] = key
    return ctx.cache["repertoire-entries"]


def on_checkpoint(ctx: RunContext) -> None:
    out = ctx.out_dir
    assert out is not None  # the artifact hooks run only in a run with a folder
    if (out / "archive.npz").exists():
        _write(ctx)


def finalize(ctx: RunContext) -> None:
    out = ctx.out_dir
    assert out is not None  # the artifact hooks run only in a run with a folder
    if not (out / "archive.npz").exists():
        return
    entries = _write(ctx)
    if not entries:
        ctx.log("repertoire: no standing step inside the archive's box yet")
        return
    ctx.log(f"repertoire: {len(entries)} standing steps -> repertoire/ (index.json, one "
            ".motion each)")
    sheet = spread(entries, 6)
    try:
        contact_sheet(out / "repertoire", sheet, out / "repertoire" / "contact_sheet.mp4",
                      robot=None if ctx.problem.steps.name == "closed_form"
                      else ctx.problem.robot)
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
        from evomotion.sim.robots.nao.replay import simulate_motion

        runs = [simulate_motion(read_cell(folder, e), hold_s=hold_s) for e in entries]
        return render_video(np.concatenate([r["qpos"] for r in runs]), runs[0]["dt"], video)
    from evomotion.sim.play import play_motion, robot_camera

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
