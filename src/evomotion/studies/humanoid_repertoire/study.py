"""``humanoid-repertoire``: a repertoire of NAO steps by quality-diversity (CMA-ME)."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from evomotion.errors import InputError
from evomotion.studies.base import Study, lazy_hook
from evomotion.studies.humanoid_repertoire.problem import (
    FALLEN_OBJECTIVE,
    HumanoidRepertoireConfig,
    make_problem,
)
from evomotion.studies.view import StudyView, lazy

cli = typer.Typer(help="A repertoire of steps (dx, dy, dtheta) of a NAO or another biped "
                       "(--robot) by CMA-ME.",
                  no_args_is_help=True)


@cli.command("pick")
def pick_cmd(run: Path = typer.Argument(..., help="a humanoid-repertoire run folder"),
             dx: float = typer.Option(..., "--dx", help="forward displacement (m), within "
                                                        "+-10"),
             dy: float = typer.Option(0.0, "--dy", help="leftward displacement (m), within "
                                                        "+-10"),
             dtheta: float = typer.Option(0.0, "--dtheta", help="turn, degrees (+ = left), "
                                                                "within +-360"),
             json_out: bool = typer.Option(False, "--json", help="JSON on stdout")) -> None:
    """The repertoire's step nearest the request: its .motion and measured behaviour."""
    from evomotion.studies.humanoid_repertoire.step_planning import pick

    r = pick(run, dx, dy, dtheta)
    if json_out:
        typer.echo(json.dumps(r, indent=2))
        return
    m = r["measured"]
    typer.echo(f"{r['file']}: cell {r['cell']}, measured dx {m['dx_m']:+.3f} m, dy "
               f"{m['dy_m']:+.3f} m, dtheta {m['dtheta_deg']:+.1f} deg, objective "
               f"{r['objective']:.3f}")


@cli.command("export")
def export_cmd(run: Path = typer.Argument(..., help="a humanoid-repertoire run folder"),
               hold: float = typer.Option(None, "--hold", help="the hold (s, 0 to 60) "
                                                               "recorded in index.json; "
                                                               "default: the run's "
                                                               "problem.hold_s")) -> None:
    """Rebuild repertoire/ (one .motion per standing cell, index.json) from archive.npz."""
    from evomotion.studies.humanoid_repertoire.artifacts import export

    folder, entries = export(run, hold)
    typer.echo(f"{len(entries)} standing steps -> {folder / 'repertoire'}")


@cli.command("walk-to")
def walk_to_cmd(run: Path = typer.Argument(..., help="a humanoid-repertoire run folder (a "
                                                     "chain of its steps), or a "
                                                     "humanoid-walk run (its closed-loop "
                                                     "walk controller)"),
                x: float = typer.Option(..., "--x", help="target forward (m), within +-10"),
                y: float = typer.Option(0.0, "--y", help="target left (m), within +-10"),
                theta: float = typer.Option(0.0, "--theta", help="target heading (deg), "
                                                                 "within +-360"),
                video: Path = typer.Option(None, "--video", help="write an MP4 of the walk"),
                out: Path = typer.Option(None, "--out", help="the chained .motion (default: "
                                                             "in the run folder)"),
                json_out: bool = typer.Option(False, "--json", help="JSON on stdout")) -> None:
    """Walk to a pose: a sequence of repertoire steps (A*), chained and played, or a walk
    controller's closed-loop walk."""
    from evomotion.studies.humanoid_repertoire.step_planning import walk_to

    if _is_controller_run(run):
        r = _controller_walk_to(run, x, y, theta, video, out)
        if json_out:
            typer.echo(json.dumps(r, indent=2))
            return
        typer.echo(f"walk controller, {r['walk_s']:.1f} s walking -> ({r['reached']['x_m']:+.3f}"
                   f", {r['reached']['y_m']:+.3f}) m, {r['reached']['theta_deg']:+.1f} deg: "
                   f"error {r['position_error_m']:.3f} m, {r['heading_error_deg']:.1f} deg, "
                   f"{'FELL' if r['fell'] else 'stayed up'}"
                   + (f"; video {r['video']}" if r["video"] else ""))
        if r.get("video_skipped"):
            typer.echo(f"video skipped: {r['video_skipped']}", err=True)
        return
    r = walk_to(run, x, y, theta, video=video, out=out)
    if json_out:
        typer.echo(json.dumps(r, indent=2))
        return
    typer.echo(f"{r['steps']} steps -> ({r['reached']['x_m']:+.3f}, {r['reached']['y_m']:+.3f}"
               f") m, {r['reached']['theta_deg']:+.1f} deg: error {r['position_error_m']:.3f}"
               f" m, {r['heading_error_deg']:.1f} deg, {'FELL' if r['fell'] else 'stayed up'}"
               f"; {r['motion']}")


def _is_controller_run(run: Path) -> bool:
    from evomotion.run.config import study_of_run

    return study_of_run(run) == "humanoid-walk"


def _controller_walk_to(run: Path, x: float, y: float, theta: float, video: Path | None,
                        out: Path | None) -> dict:
    """``walk-to`` with a humanoid-walk run: checks, then the closed-loop walk."""
    from evomotion.outfile import check_target
    from evomotion.studies.humanoid_repertoire.controller_walk_to import controller_walk_to
    from evomotion.studies.humanoid_repertoire.step_planning import check_request

    check_request(("--x", "--y", "--theta"), x, y, theta)
    if out is not None:
        raise InputError("--out: a walk controller's walk is closed loop, not a chain of "
                         "motions; there is no .motion to write")
    if video is not None:
        if video.suffix.lower() != ".mp4":
            raise InputError(f"--video {video}: expected a .mp4 path")
        video = check_target(video, "video (--video)")
    return controller_walk_to(run, x, y, theta, video)


ARTIFACTS = "evomotion.studies.humanoid_repertoire.artifacts"

STUDY = Study(
    name="humanoid-repertoire",
    description="A repertoire of NAO H25 steps in MuJoCo (or another biped's, --robot): "
                "each cell of a (dx, dy, dtheta) grid holds the most stable step that does "
                "it, found by CMA-ME; one Webots .motion per cell, pick and walk-to.",
    problem_config=HumanoidRepertoireConfig,
    make_problem=make_problem,
    defaults={
        "algorithm": {"name": "cma_me", "emitters": 4, "pop_size": 16, "sigma0": 0.15,
                      "qd_offset": FALLEN_OBJECTIVE},
        "run": {"generations": 380, "checkpoint_every": 50},
    },
    presets={"map_elites": {"algorithm": {"name": "map_elites", "pop_size": 64,
                                          "qd_offset": FALLEN_OBJECTIVE}}},
    preset_notes={"map_elites": "MAP-Elites (iso+line) instead of CMA-ME, same budget"},
    core_algorithms=("cma_me", "map_elites"),
    on_checkpoint=lazy_hook(ARTIFACTS, "on_checkpoint"),
    finalize=lazy_hook(ARTIFACTS, "finalize"),
    best_record=lazy_hook(ARTIFACTS, "best_record"),
    cli=cli,
    # the rule write_repertoire exports by: a fallen elite scores below FALLEN_OBJECTIVE + 1
    # (and the best step of any recorded generation, replayed from the ready pose)
    view=StudyView(motions=True, archive_map=True, archive_fallen_at=FALLEN_OBJECTIVE + 1.0,
                   genome_motion=lazy(ARTIFACTS, "genome_motion")),
    smoke=("algorithm.emitters=2", "algorithm.pop_size=4", "problem.hold_s=0.2",
           ),
)
