"""The ``evomotion`` command line (thin: parsing and error reporting only)."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path
from typing import Annotated, Any

import typer

from evomotion.errors import ClusterError, InputError
from evomotion.studies import (
    OLD_STUDY_NAMES,
    STUDIES,
    all_studies,
    get_study,
    study_with_preset,
)

app = typer.Typer(add_completion=False, no_args_is_help=True, pretty_exceptions_enable=False,
                  help="Evolve and search robot motions: gaits, steps, kicks, reaches, plans.")

#: the [run] keys a resume may change: limits, checkpointing, the evaluator and the loggers

SetOpt = Annotated[list[str] | None, typer.Option("--set", help="Override, e.g. run.seed=3")]


@app.command("studies")
def studies_cmd() -> None:
    """List the studies with one-line descriptions, methods and presets."""
    from evomotion.run.config import default_algorithm, study_algorithms

    for s in all_studies():
        typer.echo(f"{s.name:16s} {s.description}")
        algs = ", ".join(study_algorithms(s))
        d0, d = default_algorithm(s, ""), default_algorithm(s)  # "": no robot (env) given
        other = f"; {d} where problem.{s.defaults_key} has no defaults below" \
            if d0 != d else ""
        typer.echo(f"{'':16s}   methods: {algs} (default {d0}{other})")
        flag = "--robot" if s.defaults_key == "robot" else f"--set problem.{s.defaults_key}="
        sep = " " if s.defaults_key == "robot" else ""
        for p in (*s.presets, *s.preset_studies):
            typer.echo(f"{'':16s}   --preset {p}: {s.preset_notes.get(p, '')}")
            for r, sections in s.robot_presets.get(p, {}).items():  # its own on these
                if sections != s.presets.get(p):
                    keys = ", ".join(f"{sec}.{k}" for sec, v in sections.items() for k in v
                                     if k != "name")
                    typer.echo(f"{'':16s}     with {flag}{sep}{r}: its own ({keys})")
        # "": the key not given; its field's default names the same one (gym's Hopper-v5)
        # or none ("": the study's own robot, whose defaults equal the named one's)
        unset = {f.name: f.default for f in dataclasses.fields(s.problem_config)
                 if f.default is not dataclasses.MISSING}.get(s.defaults_key, "")
        for r, sections in s.robot_defaults.items():
            if not r:  # the study's own robot: listed under its name
                continue
            keys = ", ".join(f"{sec}.{k}" + (f"={x}" if (sec, k) == ("algorithm", "name") else "")
                             for sec, v in sections.items() for k, x in v.items())
            also = f" (also without {flag.rstrip('=')})" \
                if s.robot_defaults.get("") == sections and unset in ("", r) else ""
            typer.echo(f"{'':16s}   {flag}{sep}{r}: defaults of its own ({keys}){also}")


@app.command("run")
def run_cmd(
    study: Annotated[str, typer.Argument(help="Study name (see 'evomotion studies').")],
    config: Annotated[Path | None, typer.Option("--config", "-c", help="TOML config")] = None,
    sets: SetOpt = None,
    out: Annotated[Path | None, typer.Option("--out", help="Run folder")] = None,
    evaluator: Annotated[str | None, typer.Option(help="serial, process, ray, dask")] = None,
    workers: Annotated[int | None, typer.Option(help="Worker count (0: all cores)")] = None,
    address: Annotated[str | None, typer.Option(help="Cluster address (ray/dask)")] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No console output")] = False,
    preset: Annotated[str | None, typer.Option(
        help="Named setting, e.g. 'paper' (the source paper's literal one; 'seed' is its old "
             "name); default: best known")] = None,
    overwrite: Annotated[bool, typer.Option(
        "--overwrite", help="Empty --out first if it already holds a run")] = False,
    robot: Annotated[str | None, typer.Option(
        help="The robot: a bundled spec (nao, the default; op3, dm-humanoid, dm-quadruped) "
             "or a spec .toml (recorded as an absolute path)")] = None,
) -> None:
    """Run STUDY and write a run folder (config, stats, checkpoints, plots, artifacts)."""
    from evomotion.run.config import current_preset_name, resolve_config
    from evomotion.run.folder import make_run_dir
    from evomotion.run.runner import run_study

    s, preset = study_with_preset(study, preset)  # a preset may be another study
    overrides = list(sets or [])
    if robot is not None:
        import dataclasses

        if "robot" not in {f.name for f in dataclasses.fields(s.problem_config)}:
            raise InputError(f"--robot: study {s.name!r} runs only its own robot")
        from evomotion.sim.robots import bundled_robots, spec_path

        if robot not in bundled_robots():  # a spec file (spec_path: one line if neither):
            robot = str(spec_path(robot).resolve())  # recorded absolute: resume anywhere
        overrides.insert(0, f"problem.robot={robot!r}")
    for key, val in (("evaluator", evaluator), ("workers", workers), ("address", address)):
        if val is not None:
            overrides.append(f"run.{key}={val!r}" if isinstance(val, str) else f"run.{key}={val}")
    if current_preset_name(s, preset) != preset:
        typer.echo(f"note: --preset {preset} is the old name of "
                   f"--preset {current_preset_name(s, preset)}", err=True)
    cfg = resolve_config(s, config, overrides, preset=preset)
    top = _first_missing(Path(out) if out is not None else Path("runs"))
    out_dir = make_run_dir(s.name, out)
    if out is None and top is None:  # runs/ was there: the named folder in it is always new
        top = out_dir.absolute()
    try:
        res = run_study(s, cfg, out_dir, quiet=quiet, overwrite=overwrite)
    except (InputError, KeyboardInterrupt):
        _remove_empty(out_dir, top)  # refused before anything was written: no folder left
        raise
    _finish(res, quiet)


def _first_missing(path: Path) -> Path | None:
    """The outermost folder of ``path`` (absolute) that does not exist yet, or None."""
    try:
        p = path.absolute()
        missing = None
        for q in (p, *p.parents):
            if q.exists() or q.is_symlink():
                break
            missing = q
        return missing
    except (OSError, ValueError):
        return None


def _remove_empty(out_dir: Path, top: Path | None) -> None:
    """Remove ``out_dir`` and its parents up to ``top`` (the folders this command made), each
    only while it is empty."""
    if top is None:
        return
    p = out_dir.absolute()
    while True:
        try:
            if not p.is_dir() or any(p.iterdir()):
                return
            p.rmdir()
        except OSError:
            return
        if p == top or p.parent == p:
            return
        p = p.parent


def _finish(res, quiet: bool) -> None:
    from evomotion.run.runner import EXIT_NO_FINITE

    if res.exit_code == EXIT_NO_FINITE:
        typer.echo(f"error: no individual got a finite fitness; best.json holds null "
                   f"(see {res.out_dir}/log.txt)", err=True)
        raise typer.Exit(res.exit_code)
    if not quiet:
        typer.echo(f"{res.stop_reason}: best fitness {res.best_fitness:.6g} after "
                   f"{res.generation} generations -> {res.out_dir}", err=True)
    raise typer.Exit(res.exit_code)


@app.command("resume")
def resume_cmd(
    run_dir: Annotated[Path, typer.Argument(help="Run folder with checkpoints/")],
    evaluator: Annotated[str | None, typer.Option(help="Continue with another evaluator")] = None,
    workers: Annotated[int | None, typer.Option(help="Worker count")] = None,
    address: Annotated[str | None, typer.Option(help="Cluster address (ray/dask)")] = None,
    sets: Annotated[list[str] | None, typer.Option(
        "--set", help="Raise a [run] limit, e.g. run.generations=300")] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q")] = False,
) -> None:
    """Continue an interrupted run from its last checkpoint (or extend a finished one)."""
    from evomotion.run.config import parse_value
    from evomotion.run.resume import resume_config
    from evomotion.run.runner import run_study

    changes: dict = {}
    for key, val in (("evaluator", evaluator), ("workers", workers), ("address", address)):
        if val is not None:
            changes[f"run.{key}"] = val
    for item in sets or []:
        key, eq, text = item.partition("=")
        if not eq:
            raise InputError(f"--set {item!r}: expected section.key=value")
        changes[key.strip()] = parse_value(text.strip())
    s, cfg = resume_config(run_dir, None, changes, resolve=get_study)
    _finish(run_study(s, cfg, run_dir, quiet=quiet, resume=True), quiet)


@app.command("stop")
def stop_cmd(
    run_dir: Annotated[Path, typer.Argument(help="A running run's folder")],
) -> None:
    """Stop a running run as Ctrl-C would (it checkpoints; 'evomotion resume' continues it).

    Only a live process that verifiably is that run is signalled (the pid, start time, boot
    and host its run.lock records); a stale lock is reported, and nothing is signalled."""
    import signal

    from evomotion.run.lock import signal_owner

    if not (run_dir / "run.lock").exists():
        raise InputError(f"{run_dir}: not a run folder with a run.lock")
    pid = signal_owner(run_dir, signal.SIGTERM)
    typer.echo(f"sent SIGTERM to the run's process {pid}", err=True)


@app.command("plot")
def plot_cmd(
    run_dirs: Annotated[list[Path], typer.Argument(help="One or more run folders")],
    out: Annotated[Path | None, typer.Option(help="Output stem (.png and .svg)")] = None,
) -> None:
    """Fitness per generation (one run; a quality-diversity run also gets its coverage /
    QD-score curves and the archive heat map) or median/IQR against evaluations (several)."""
    from evomotion.run.plots import plot_archive, plot_fitness, plot_qd, plot_runs

    for d in run_dirs:
        if not (d / "stats.csv").exists():
            raise InputError(f"{d}: not a run folder (no stats.csv)")
    if out is not None:  # a path the user names: checked before anything is drawn
        from evomotion.outfile import check_target

        for suffix in (".png", ".svg"):
            check_target(out.with_suffix(suffix), "plot (--out)")
    if len(run_dirs) == 1:
        d = run_dirs[0]
        paths = plot_fitness(d / "stats.csv", out or d / "plots" / "fitness")
        if (d / "archive.npz").exists() and out is None:
            paths += plot_qd(d / "stats.csv", d / "plots" / "qd")
            paths += plot_archive(d / "archive.npz", d / "plots" / "archive")
    else:
        paths = plot_runs([d / "stats.csv" for d in run_dirs], out or Path("runs-comparison"))
    for p in paths:
        typer.echo(str(p))


@app.command("replay")
def replay_cmd(
    motion: Annotated[Path, typer.Argument(
        help="A Webots .motion file, or a policy run folder (gym, humanoid-balance) or its "
             "policy.npz")],
    json_out: Annotated[bool, typer.Option("--json", help="Only JSON on stdout")] = False,
    video: Annotated[Path | None, typer.Option(help="Write an MP4 of the replay")] = None,
    hold: Annotated[float | None, typer.Option(
        help="A .motion: seconds held in the last pose (default 1)")] = None,
    friction: Annotated[float | None, typer.Option(
        help="Scale of every friction coefficient (floor and soles; > 0)")] = None,
    mass_scale: Annotated[float | None, typer.Option(
        "--mass-scale", help="Scale of every link mass and inertia (> 0)")] = None,
    push: Annotated[float | None, typer.Option(
        help="Lateral push impulse on the torso at mid-motion, N s (+ = to the left)")] = None,
    trials: Annotated[int | None, typer.Option(
        help="Also replay in N random perturbed worlds (fall rate, forward displacement)")
    ] = None,
    seed: Annotated[int, typer.Option(help="Seed of the --trials worlds")] = 0,
    start: Annotated[str | None, typer.Option(
        "--from", help="Initial state: standing, face-down or face-up")] = None,
    stress: Annotated[int | None, typer.Option(
        help="A policy: play it in N unseen perturbed worlds and print its survival")] = None,
    command: Annotated[str | None, typer.Option(
        help="A walk controller: vx,vy,w (m/s, m/s, rad/s) or a file of lines 't_s, vx, vy, "
             "w'; default the run's random commands")] = None,
    duration: Annotated[float | None, typer.Option(
        help="A walk controller: seconds walked (default 20)")] = None,
) -> None:
    """Play a Webots .motion on the NAO model: displacement, heading change, fall;
    optionally in perturbed worlds or from lying (docs/humanoid-step.md). A policy run
    folder: its policy in unseen episodes or pushed worlds (docs/gym.md,
    docs/humanoid-balance.md)."""
    from evomotion.sim.robots.nao.replay import StressOptions, replay_command

    if not motion.exists():
        raise InputError(f"{motion}: no such motion file")
    if motion.is_dir() or motion.suffix == ".npz":  # a run folder: its study replays it
        if friction is not None or mass_scale is not None or start is not None \
                or hold is not None:
            raise InputError("replay of a policy: --friction, --mass-scale, --from and --hold "
                             "apply to a .motion; use --stress N (--push P sets the push, N s)")
        from evomotion.run.config import config_from_run_dir
        from evomotion.studies import get_study

        folder = motion.parent if motion.suffix == ".npz" else motion
        study = get_study(config_from_run_dir(folder)[0])
        if study.replay_run is None:
            raise InputError(f"replay {motion}: a {study.name} run has nothing to replay here "
                             "(a .motion file of it can be given instead)")
        walk = {k: v for k, v in (("command", command), ("duration_s", duration))
                if v is not None}
        if walk and study.name != "humanoid-walk":
            raise InputError("replay: --command and --duration are for a walk controller run "
                             f"(humanoid-walk), not a {study.name} run")
        study.replay_run(motion, json_out=json_out, video=video,
                         stress=stress if stress is not None else trials, seed=seed,
                         push_ns=push, **walk)
        return
    if command is not None or duration is not None:
        raise InputError("replay: --command and --duration are for a walk controller run "
                         "folder, not a .motion")
    if stress is not None:
        raise InputError("--stress is for a policy run folder; a .motion takes --trials N")
    options = StressOptions(friction=friction, mass_scale=mass_scale, push_ns=push,
                            trials=trials, seed=seed, start=start)
    replay_command(motion, json_out=json_out, video=video,
                   hold_s=1.0 if hold is None else hold, stress=options)


@app.command("export")
def export_cmd(
    motion: Annotated[Path, typer.Argument(help="A Webots .motion file")],
    naoqi: Annotated[Path | None, typer.Option("--naoqi", help="Write a NAOqi Python script")]
    = None,
    json_out: Annotated[Path | None, typer.Option("--json", help="Write a JSON keyframe file")]
    = None,
    clip: Annotated[bool, typer.Option(help="Clip angles to the joint ranges")] = False,
    speed_margin: Annotated[float, typer.Option(
        help="Fraction of each motor's no-load speed allowed, in (0, 1]")] = 1.0,
) -> None:
    """Check a .motion against a real NAO's limits; write a NAOqi script and/or keyframes."""
    from evomotion.sim.robots.nao.export import export_command

    for line in export_command(motion, naoqi, json_out, clip, speed_margin):
        typer.echo(line)


@app.command("studio")
def studio_cmd(
    runs_dir: Annotated[Path, typer.Argument(help="Folder of run folders")] = Path("runs"),
    port: Annotated[int, typer.Option(help="TCP port")] = 8765,
    host: Annotated[str, typer.Option(help="Address to listen on (others: warned)")]
    = "127.0.0.1",
) -> None:
    """Watch, compare, start and stop runs in the browser (needs the \\[studio] extra).

    The URL printed at start carries the access token (or set EVOMOTION_STUDIO_TOKEN)."""
    import os
    import socket

    if not 1 <= port <= 65535:
        raise InputError(f"--port: expected 1..65535, got {port}")
    if not runs_dir.is_dir():
        raise InputError(f"{runs_dir}: no such folder of runs")
    try:
        import nicegui  # noqa: F401
    except ImportError:
        raise InputError("the studio needs NiceGUI: pip install 'evomotion[studio]'") from None
    try:
        with socket.create_server((host, port)):
            pass
    except OSError as e:
        raise InputError(f"--host {host} --port {port}: cannot listen there "
                         f"({e.strerror or e})") from None
    from evomotion.studio.app import serve

    serve(runs_dir, host, port, os.environ.get("EVOMOTION_STUDIO_TOKEN") or None)


def _mount_study_app(argv: list[str]) -> None:
    """Mount the ``evomotion <study> ...`` command groups: the one named on the command line,
    or all of them for the top-level help (importing every study costs a second or two)."""
    if len(argv) > 1 and (argv[1] in STUDIES or argv[1] in OLD_STUDY_NAMES):
        names = [argv[1]]  # an old name: its study's commands under the name given
    elif len(argv) == 1 or argv[1] in ("--help", "-h"):
        names = list(STUDIES)
    else:
        return
    for name in names:
        s = get_study(name)
        if s.cli is not None:
            app.add_typer(s.cli, name=name, help=s.description)


def _click_exceptions() -> Any:
    """The exceptions module of the click that typer runs on (typer >= 0.2x ships its own
    copy as ``typer._click``; earlier versions use click itself)."""
    import importlib

    try:
        return importlib.import_module("typer._click.exceptions")
    except ImportError:
        return importlib.import_module("click.exceptions")


def main(argv: list[str] | None = None) -> None:
    cx = _click_exceptions()
    argv = list(sys.argv if argv is None else argv)
    try:
        _mount_study_app(argv)
        # not standalone: click's own errors come back here, to be said in one line
        code = app(args=argv[1:], prog_name="evomotion", standalone_mode=False)
    except cx.UsageError as e:  # a bad option or argument: one line, as every bad input
        if type(e).__name__ == "NoArgsIsHelpError":  # a bare group: its help, as before
            typer.echo(e.ctx.get_help() if e.ctx is not None else str(e))
            sys.exit(2)
        where = e.ctx.command_path if e.ctx is not None else "evomotion"
        typer.echo(f"error: {e.format_message()} (see '{where} --help')", err=True)
        sys.exit(2)
    except typer.Abort:
        typer.echo("error: interrupted", err=True)
        sys.exit(130)
    except InputError as e:
        typer.echo(f"error: {e}", err=True)
        sys.exit(2)
    except ClusterError as e:
        typer.echo(f"error: {e}; the last completed generation is checkpointed: continue with "
                   "'evomotion resume RUN_DIR --evaluator serial' (or process)", err=True)
        sys.exit(4)
    except OSError as e:  # a file the checks above did not foresee (a disk that failed)
        from evomotion.outfile import reason

        where = f"{e.filename}: " if getattr(e, "filename", None) else ""
        typer.echo(f"error: {where}{reason(e)}", err=True)
        sys.exit(2)
    except KeyboardInterrupt:  # before a run loop began (a run's own is a checkpoint)
        typer.echo("error: interrupted", err=True)
        sys.exit(130)
    except MemoryError:
        typer.echo("error: out of memory (an input asked for more than this machine has)",
                   err=True)
        sys.exit(2)
    # as click's standalone mode did: always exit, with typer.Exit(n)'s n (returned when not
    # standalone) or 0
    sys.exit(code if isinstance(code, int) else 0)


if __name__ == "__main__":
    main()
