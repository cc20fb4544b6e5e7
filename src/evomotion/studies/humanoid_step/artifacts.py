"""Run-folder artifacts of ``humanoid-step``: ``best.motion``, ``best.mp4``, ``fitness.png``,
and the exports for a real NAO, ``best_naoqi.py`` and ``best_keyframes.json``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from evomotion.outfile import atomic_write_text, write_json
from evomotion.run.context import RunContext
from evomotion.sim.motion import Motion, format_motion
from evomotion.studies.humanoid_step.problem import HumanoidStepProblem

POSE_MS = 40  # Webots motions (and the paper's Motion.save) sample a pose every 40 ms


def genome_motion(problem: HumanoidStepProblem, genome: np.ndarray) -> Motion:
    """The whole robot (the NAO's 22 joints, or another robot's actuated joints) every 40 ms
    over the step time, as a Webots motion."""
    times_ms = np.arange(0, int(round(problem.cfg.motion_s * 1000)) + 1, POSE_MS)
    ctrl = problem.controls(np.atleast_2d(genome), times_ms / 1000.0)[0]
    joints = tuple(problem.robot.joints)
    return Motion(joints, times_ms, ctrl)


def write_best_motion(ctx: RunContext) -> Path | None:
    if ctx.best_genome is None or not np.all(np.isfinite(ctx.best_genome)):
        return None
    out = ctx.out_dir
    assert out is not None  # the artifact hooks run only in a run with a folder
    path = out / "best.motion"
    atomic_write_text(path, format_motion(genome_motion(ctx.problem, ctx.best_genome)))
    return path


def write_exports(ctx: RunContext) -> bool:
    """``best_naoqi.py`` and ``best_keyframes.json`` beside ``best.motion``, when the best
    motion passes the real-NAO checks (:mod:`evomotion.sim.robots.nao.joint_limits`); otherwise the
    reason goes to the log, nothing is written and older exports are removed (the run does
    not fail for it)."""
    if ctx.best_genome is None or not np.all(np.isfinite(ctx.best_genome)):
        return False
    export = ctx.problem.robot.capability("naoqi_export", "humanoid-step's NAOqi exports")
    return export.write_run_exports(genome_motion(ctx.problem, ctx.best_genome), ctx.out_dir,
                                    ctx.log)


def on_checkpoint(ctx: RunContext) -> None:
    write_best_motion(ctx)


def finalize(ctx: RunContext) -> None:
    """best.motion, its replay summary (best_replay.json), best.mp4 and fitness.png."""
    from evomotion.run.plots import plot_fitness
    from evomotion.sim.motion import read_motion
    from evomotion.sim.robots.nao.replay import replay_motion

    out = ctx.out_dir
    assert out is not None  # the artifact hooks run only in a run with a folder
    stats = out / "stats.csv"
    if stats.exists():
        plot_fitness(stats, out / "fitness", title="humanoid-step")
    path = write_best_motion(ctx)
    if path is None:
        return
    if not ctx.problem.robot.has("webots_names"):  # replayed as Webots plays it: the NAO
        return finalize_robot(ctx)
    write_exports(ctx)
    video: Path | None = out / "best.mp4"
    summary, skipped = replay_motion(read_motion(path), video, ctx.problem.cfg.hold_s)
    if skipped is not None:  # no GL backend: keep everything but the video
        ctx.log(f"best.mp4 skipped: {skipped}")
        video = None
    write_json(out / "best_replay.json", summary)
    dx, dy = summary["displacement_m"]
    ctx.log(f"best.motion replayed: dx={dx:+.3f} m dy={dy:+.3f} m, "
            f"{'fell' if summary['fell'] else 'stayed up'}"
            + (f"; video {video.name}" if video else ""))


def finalize_robot(ctx: RunContext) -> None:
    """Another robot than the NAO: the best genome simulated as evaluated (its own model),
    ``best_replay.json`` and ``best.mp4`` (no NAO exports)."""
    from evomotion.sim.render import RenderUnavailableError, render_video
    from evomotion.sim.rollout import torso_track

    problem, robot = ctx.problem, ctx.problem.robot
    out = ctx.out_dir
    assert out is not None  # the artifact hooks run only in a run with a folder
    if ctx.best_genome is None:  # finalize calls it only after best.motion
        return
    states, sensors = problem.simulate(np.atleast_2d(ctx.best_genome))
    ev = problem.score(states, sensors)
    track = torso_track(states)
    summary = {"robot": robot.name, "displacement_m": [float(ev.metrics["forward_m"][0]),
                                                       float(ev.metrics["lateral_m"][0])],
               "heading_change_rad": float(ev.metrics["heading_change_rad"][0]),
               "fell": bool(ev.metrics["fell"][0]),
               "time_to_fall_s": float(ev.metrics["time_to_fall_s"][0]),
               "torso_height_m": [float(track.xyz[0, 0, 2]), float(track.xyz[0, -1, 2])]}
    write_json(out / "best_replay.json", summary)
    video = out / "best.mp4"
    try:
        if not robot.xml:
            raise RuntimeError("the robot's edited model cannot be written as MJCF text")
        from evomotion.sim.play import robot_camera

        render_video(states[0, :, 1:1 + robot.model.nq], problem.dt, video,
                     model_xml=robot.xml, camera=robot_camera(robot))
        video_note = f"; video {video.name}"
    except (RenderUnavailableError, RuntimeError) as e:
        ctx.log(f"best.mp4 skipped: {e}")
        video_note = ""
    dx, dy = summary["displacement_m"]
    ctx.log(f"best step on {robot.name}: dx={dx:+.3f} m dy={dy:+.3f} m, "
            f"{'fell' if summary['fell'] else 'stayed up'}"
            + video_note)
