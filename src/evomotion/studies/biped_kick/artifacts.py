"""Run-folder artifacts of ``biped-kick``.

- ``best.motion``: the whole straight kick (stand, shift, lift, kick, retract, shift back), 22
  joints, 20 ms poses, exactly the key poses that were simulated; ``kicks/aim_+20.motion`` and
  the rest: the same kick aimed from -30 to +30 degrees (ball placed as ``best_kicks.json`` says);
  on a robot whose kicker has a mirror image (the NAO), ``kicks/left_aim_+20.motion`` and the
  rest: the left-foot kicks, each the right-foot kick at the opposite aim in mirror image (the
  ball mirrored too: the opposite aim's row of ``best_kicks.json``, its ``ball_offset_y_m``
  negated, measured from the left sole's centre line);
- ``best_naoqi.py`` / ``best_keyframes.json``: exports for a real NAO when the kick passes the
  joint-range and motor-speed checks;
- ``best.mp4``: the straight kick with the ball, camera on robot and ball;
- ``plots/kick_foot.png`` (foot trajectory), ``plots/kick_zmp.png`` (CoP margin and path
  over the support polygons) and ``plots/kick_progress.png`` (the search, feasible kicks only);
- ``best_kicks.json``: one kick per aim (-30..+30 deg, step 10): distance, angle error, fall,
  minimum ZMP margin, ``stable`` (no fall, ZMP margin kept; the joint limits are checked on
  the motion files), where the ball must lie relative to the right sole;
- ``best.json`` key ``genes``: the genes by name.
"""

from __future__ import annotations

from typing import Any, TypeGuard

import numpy as np

from evomotion.outfile import atomic_write_text, write_json
from evomotion.run.context import RunContext
from evomotion.sim.motion import Motion, format_motion
from evomotion.studies.biped_kick.motion import ball_offset, named

AIMS_DEG = (-30, -20, -10, 0, 10, 20, 30)


def _ok(genome: Any) -> TypeGuard[np.ndarray]:
    return genome is not None and bool(np.all(np.isfinite(genome)))


def best_record(ctx: RunContext) -> dict[str, Any]:
    if not _ok(ctx.best_genome):
        return {}
    return {"genes": named(ctx.best_genome),
            "feasible": bool(ctx.best_metrics.get("feasible", 0.0) > 0)}


def write_motions(ctx: RunContext) -> None:
    if not _ok(ctx.best_genome):
        return
    out = ctx.out_dir
    assert out is not None  # the artifact hooks run only in a run with a folder
    kick_motion = ctx.problem.kicker.kick_motion  # the robot's joints
    atomic_write_text(out / "best.motion", format_motion(kick_motion(ctx.best_genome)))
    mirror = getattr(ctx.problem.kicker, "mirror", None)
    for a in AIMS_DEG:  # kicks/ is the run's own folder
        motion = kick_motion(ctx.best_genome, np.radians(a))
        atomic_write_text(out / "kicks" / f"aim_{a:+d}.motion", format_motion(motion),
                          "aimed kick", mkdir=True)
        if mirror is not None:
            atomic_write_text(out / "kicks" / f"left_aim_{-a:+d}.motion",
                              format_motion(left_foot(motion, mirror)), "aimed kick")


def left_foot(right: Motion, mirror: Any) -> Motion:
    """The right-foot kick ``right`` played by the left foot: its poses in mirror image."""
    return Motion(right.joints, right.times_ms.copy(), mirror(right.values),
                  list(right.pose_names))


def genome_motion(problem: Any, genome: np.ndarray) -> Motion:
    """The straight kick of ``genome`` (the studio replays a generation's best with it)."""
    return problem.kicker.kick_motion(genome)


def on_checkpoint(ctx: RunContext) -> None:
    write_motions(ctx)


def aim_table(problem: Any, genome: np.ndarray) -> list[dict[str, float]]:
    """One nominal kick per aim of :data:`AIMS_DEG`."""
    aims = np.radians(np.array(AIMS_DEG, dtype=float))
    g = np.repeat(np.atleast_2d(genome), len(aims), axis=0)
    k = problem.kicks(g, aims, problem.ball_xy(g, aims))
    feasible = ~k["fell"] & (k["zmp_deficit_m_s"] <= 0)
    return [{"aim_deg": float(a), "distance_along_m": float(k["along_m"][i]),
             "angle_error_deg": float(np.degrees(k["angle_error_rad"][i])),
             "fell": bool(k["fell"][i]), "min_margin_m": float(k["min_margin_m"][i]),
             "stable": bool(feasible[i]),
             "ball_offset_y_m": float(ball_offset(genome[None], aims[i])[0])}
            for i, a in enumerate(AIMS_DEG)]


def finalize(ctx: RunContext) -> None:
    """Motions, exports, the per-aim table, the plots and the video of the best kick."""
    from evomotion.sim.render import RenderUnavailableError, render_video
    from evomotion.sim.state import state_qpos_all
    from evomotion.studies.biped_kick.kick_plots import plot_foot, plot_progress, plot_zmp
    from evomotion.studies.biped_kick.problem import FLOOR_M, support_analysis

    if not _ok(ctx.best_genome):
        return
    write_motions(ctx)
    out = ctx.out_dir
    assert out is not None  # the artifact hooks run only in a run with a folder
    g = np.asarray(ctx.best_genome, dtype=float)
    p = ctx.problem
    if not ctx.best_metrics.get("feasible", 0.0):
        ctx.log(f"best kick is not feasible (ZMP, fall or {p.robot.name.upper()} limits "
                "violated); give the search more evaluations")
    if p.robot.has("naoqi_export"):
        p.robot.capability("naoqi_export", "biped-kick's export").write_run_exports(
            p.kicker.kick_motion(g), out, ctx.log)
    rows = aim_table(p, g)
    write_json(out / "best_kicks.json", rows)
    k = p.kicks(g[None], np.zeros(1), p.ball_xy(g[None], np.zeros(1)), keep=True)
    end = int(k["end"][0])
    times = k["times"][:end]
    sens = k["sensors"][0, :end]
    margin, cop, corners = support_analysis(sens, p.sl, p.kicker.sole_half)
    plot_foot(g, 0.0, times, sens[:, p.sl["r_sole"]], ctx.plots_dir / "kick_foot",
              feet=p.kicker.foot_trajectories(g[None], times, 0.0))
    plot_zmp(g, times, margin, cop, corners, p.cfg.zmp_margin_m, ctx.plots_dir / "kick_zmp")
    if (out / "stats.csv").exists():
        plot_progress(out / "stats.csv", FLOOR_M, ctx.plots_dir / "kick_progress")
    qpos = state_qpos_all(p.model, k["states"][0, :end])
    video = out / "best.mp4"
    try:
        render_video(qpos, p.dt, video, model_xml=p.kicker.scene_xml,
                     assets=p.robot.assets or None, camera="kick")
        video_note = f"; video {video.name}"
    except RenderUnavailableError as exc:
        ctx.log(f"best.mp4 skipped: {exc}")
        video_note = ""
    straight = rows[AIMS_DEG.index(0)]
    ctx.log(f"best kick: {straight['distance_along_m']:.2f} m straight, "
            f"{'fell' if straight['fell'] else 'stayed up'}, min ZMP margin "
            f"{1000 * straight['min_margin_m']:.1f} mm; aimed -30..+30 deg: mean angle error "
            f"{np.mean([abs(r['angle_error_deg']) for r in rows]):.1f} deg"
            + video_note)
