"""Run-folder artifacts of ``humanoid-walk-open-loop``.

- ``best.motion``: the whole walk (start-up, the repeated cycle, stop), 22 joints, 20 ms
  poses; ``walk_start.motion``, ``walk_cycle.motion`` (loop it) and ``walk_stop.motion``: its
  three parts (:mod:`.walk_motion`);
- ``best_naoqi.py`` and ``best_keyframes.json``: the exports for a real NAO, written only when
  the walk passes the joint-range and motor-speed checks;
- ``best_replay.json``: ``evomotion replay`` of ``best.motion`` with the run's hold;
- ``best.mp4``: that replay on video;
- the gait parameters by name in ``best.json`` (key ``gait``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, TypeGuard

import numpy as np

from evomotion.outfile import atomic_write_text, write_json
from evomotion.run.context import RunContext
from evomotion.sim.motion import Motion, format_motion
from evomotion.studies.humanoid_walk import foot_gait
from evomotion.studies.humanoid_walk.walk_motion import assemble, walk_parts

PART_FILES = ("walk_start.motion", "walk_cycle.motion", "walk_stop.motion")


def _ok(genome: Any) -> TypeGuard[np.ndarray]:
    return genome is not None and bool(np.all(np.isfinite(genome)))


def best_record(ctx: RunContext) -> dict[str, Any]:
    """The gait parameters by name, the period as played, and the walk's structure."""
    if not _ok(ctx.best_genome):
        return {}
    if ctx.problem.gait.name != "foot":
        return {"robot": ctx.problem.robot.name, "gait": dict(zip(
            ctx.problem.genome.names, (float(v) for v in ctx.best_genome), strict=True))}
    parts = walk_parts(ctx.best_genome, ctx.problem.cfg.walk_s)
    return {"gait": foot_gait.named(ctx.best_genome),
            "motion": {"start_s": parts.start.duration_s, "cycle_s": parts.cycle.duration_s,
                       "cycles": parts.cycles, "stop_s": parts.stop.duration_s,
                       "total_s": assemble(parts).duration_s}}


def genome_motion(problem: Any, genome: np.ndarray) -> Motion:
    """The whole walk of ``genome`` as ``best.motion`` holds it (the studio replays a
    generation's best with it)."""
    if problem.gait.name != "foot":
        return problem.motion(genome)
    return assemble(walk_parts(genome, problem.cfg.walk_s))


def write_motions(ctx: RunContext) -> Motion | None:
    """``best.motion`` and its three parts; the whole walk (``None`` without a best)."""
    if not _ok(ctx.best_genome):
        return None
    out = ctx.out_dir
    assert out is not None  # the artifact hooks run only in a run with a folder
    if ctx.problem.gait.name != "foot":  # the robot's channels every 20 ms
        whole = ctx.problem.motion(ctx.best_genome)
        atomic_write_text(out / "best.motion", format_motion(whole))
        return whole
    parts = walk_parts(ctx.best_genome, ctx.problem.cfg.walk_s)
    for name, motion in zip(PART_FILES, (parts.start, parts.cycle, parts.stop), strict=True):
        atomic_write_text(out / name, format_motion(motion))
    whole = assemble(parts)
    atomic_write_text(out / "best.motion", format_motion(whole))
    return whole


def on_checkpoint(ctx: RunContext) -> None:
    write_motions(ctx)


def finalize(ctx: RunContext) -> None:
    """The motions, the exports, the replay summary and the video."""
    from evomotion.sim.robots.nao.export import write_run_exports
    from evomotion.sim.robots.nao.replay import replay_motion

    motion = write_motions(ctx)
    if motion is None:
        return
    if ctx.problem.gait.name != "foot":
        return finalize_robot(ctx)
    out = ctx.out_dir
    assert out is not None  # the artifact hooks run only in a run with a folder
    # best_naoqi.py and best_keyframes.json only when the walk passes the real-NAO checks
    write_run_exports(motion, out, ctx.log)
    hold = ctx.problem.cfg.hold_s
    video: Path | None = out / "best.mp4"
    summary, skipped = replay_motion(motion, video, hold)
    if skipped is not None:
        ctx.log(f"best.mp4 skipped: {skipped}")
        video = None
    duration = motion.duration_s
    dx, dy = summary["displacement_m"]
    summary.update(hold_s=hold, duration_s=duration, speed_mps=dx / duration,
                   heading_deg_per_m=float(np.degrees(abs(summary["heading_change_rad"]))
                                           / max(dx, 0.01)))
    write_json(out / "best_replay.json", summary)
    ctx.log(f"best.motion replayed: {dx:+.3f} m forward, {dy:+.3f} m sideways in "
            f"{duration:.2f} s ({summary['speed_mps']:.3f} m/s over the whole motion), "
            f"{'fell' if summary['fell'] else 'stayed up'}"
            + (f"; video {video.name}" if video else ""))


def finalize_robot(ctx: RunContext) -> None:
    """Another robot: the best gait simulated as evaluated (nominal world), its summary
    (``best_replay.json``: distance, speed, straightness, fell) and ``best.mp4``."""
    from evomotion.sim.render import RenderUnavailableError, render_video

    p = ctx.problem
    out = ctx.out_dir
    assert out is not None  # the artifact hooks run only in a run with a folder
    if not _ok(ctx.best_genome):  # finalize calls it only after the best's motions
        return
    states, batch = p.simulate(np.atleast_2d(ctx.best_genome))
    ev = p.score(states, batch.ctrl, batch)
    summary = {"robot": p.robot.name, "gait_kind": p.kind,
               **{k: float(v[0]) for k, v in ev.metrics.items()},
               "walk_s": float(batch.walk_s[0]), "horizon_s": p.horizon_s}
    summary["fell"] = bool(summary["fell"])
    write_json(out / "best_replay.json", summary)
    back = 3.0 if p.kind == "biped" else 6.0  # a quadruped is longer than it is tall
    video = out / "best.mp4"
    try:
        if not p.robot.xml:
            raise RuntimeError("the robot's edited model cannot be written as MJCF text")
        from evomotion.sim.play import robot_camera

        render_video(states[0, :, 1:1 + p.model.nq], p.dt, video, model_xml=p.robot.xml,
                     camera=robot_camera(p.robot, back, least_m=1.2))
        video_note = f"; video {video.name}"
    except (RenderUnavailableError, RuntimeError) as e:
        ctx.log(f"best.mp4 skipped: {e}")
        video_note = ""
    ctx.log(f"best gait on {p.robot.name}: {summary['forward_m']:+.3f} m forward, "
            f"{summary['lateral_m']:+.3f} m sideways, {summary['speed_mps']:.3f} m/s, "
            f"straightness {summary['straightness']:.2f}, "
            f"{'fell' if summary['fell'] else 'stayed up'}"
            + video_note)
