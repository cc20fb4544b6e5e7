"""The run loop: every study runs here, through a :class:`~evomotion.run.driver.Driver`.

The loop owns the run folder, config, log, stats, best.json, checkpoints, console and
evaluator; the driver owns the method. Bit-identical resume: after every step the loop keeps a
snapshot of the driver state, the RNG state and the logger offsets (drivers whose state is too
large to copy every step are snapshotted at checkpoints only). Checkpoints (every
``run.checkpoint_every`` steps, at the end, and on Ctrl-C/SIGTERM or a crash) write that
snapshot, so a resumed run replays exactly the steps that were lost.

With ``out_dir=None`` the same loop runs without a folder (no files, no console): the
experiments of the studies use that for their many short runs.
"""

from __future__ import annotations

import dataclasses
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.core.state import rng_state
from evomotion.errors import InputError
from evomotion.outfile import WriteError
from evomotion.run.ask_tell import AskTellDriver, make_optimizer
from evomotion.run.checkpoint import save_checkpoint
from evomotion.run.config import Config, config_to_toml
from evomotion.run.console import Reporter
from evomotion.run.context import RunContext
from evomotion.run.driver import Driver
from evomotion.run.evaluators import SerialEvaluator, make_evaluator
from evomotion.run.folder import (
    atomic_write_text,
    check_new_run,
    check_resumable,
    clean_temporaries,
    prepare_new_run,
    write_json,
)
from evomotion.run.history import NAME as HISTORY_NAME
from evomotion.run.history import HistoryWriter
from evomotion.run.limits import check_memory
from evomotion.run.lock import RunLock
from evomotion.run.loggers import make_loggers
from evomotion.run.resume import config_record, restore
from evomotion.run.runlog import RunLog, sigterm_as_interrupt
from evomotion.run.stats import COLUMNS, MemoryStats, StatsWriter, diversity, population_stats
from evomotion.run.stopping import limit_reached, stop_reason
from evomotion.textio import read_json

#: the stop reasons a resume with a raised limit continues from
LIMIT_REASONS = ("generations", "max_evaluations", "target", "wall_seconds")
PHYSICS_NAME = "physics.json"  # the physics backend of a MuJoCo study and its guarantees

EXIT_INTERRUPTED = 130
EXIT_NO_FINITE = 5  # the run ended without any finite fitness


@dataclass
class RunResult:
    out_dir: Path | None
    stop_reason: str
    generation: int
    evaluations: int
    best_fitness: float
    best_genome: np.ndarray
    best_metrics: dict[str, float] = field(default_factory=dict)
    exit_code: int = 0
    driver: Driver | None = None
    state: Any = None
    rows: list[dict[str, Any]] = field(default_factory=list)  # stats rows (no-folder runs)


def build_driver(study: Any, config: Config, problem: Any) -> Driver:
    """The study's own driver for ``algorithm.name`` if it has one, else the ask/tell one."""
    own = getattr(study, "algorithms", {}).get(config.algorithm.name)
    if own is not None:
        return own[1](problem, config)
    return AskTellDriver(problem, make_optimizer(problem, config.algorithm))


def run_study(study: Any, config: Config, out_dir: Path | str | None = None,
              quiet: bool = False, resume: bool = False, problem: Any = None,
              evaluator: Any = None, overwrite: bool = False) -> RunResult:
    """Run (or resume, when ``resume``) ``study`` with ``config`` in ``out_dir``.

    ``problem`` (default: built from ``config.problem``) and ``evaluator`` (default: the one
    ``run.evaluator`` names; a given one is not closed here) serve callers that run many
    short runs on one problem. The run folder is locked while the run writes to it; a new run
    into a folder that already holds one is refused unless ``overwrite``."""
    if out_dir is None:
        if resume:
            raise InputError("resume needs a run folder")
        return _run(study, config, None, True, False, problem, evaluator)
    out_dir = Path(out_dir)
    if not resume:
        check_new_run(out_dir, overwrite)  # refused before the lock file is made
    if resume:
        check_resumable(out_dir)  # before anything is made or removed in the folder
    out_dir.mkdir(parents=True, exist_ok=True)
    # SIGTERM is Ctrl-C from the moment the lock names this process (a stop from the studio
    # during the set-up ends the run cleanly, not by the signal's default)
    with sigterm_as_interrupt(), RunLock(out_dir) as lock:
        if not resume:
            prepare_new_run(out_dir, study.name, overwrite)
        return _run(study, config, out_dir, quiet, resume, problem, evaluator,
                    stale_owner=lock.stale_owner)


def _run(study: Any, config: Config, out_dir: Path | None, quiet: bool, resume: bool,
         problem: Any, evaluator: Any, stale_owner: str | None = None) -> RunResult:
    rc = config.run
    seeded = getattr(config.problem, "with_run_seed", None)
    if seeded is not None:  # problem randomness drawn from the run seed (e.g. perturbed worlds)
        config = dataclasses.replace(config, problem=seeded(rc.seed))
    problem = problem if problem is not None else study.make_problem(config.problem)
    check_memory(study, config, problem)  # before any population array is allocated
    driver = build_driver(study, config, problem)
    if rc.evaluator != "serial" and not driver.uses_evaluator:
        raise InputError(f"run.evaluator: study {study.name!r} has no batch evaluation to "
                         f"distribute; use 'serial', got {rc.evaluator!r}")
    loggers = make_loggers(rc.loggers if out_dir is not None else (), out_dir)  # before files
    cleaned = 0
    if out_dir is not None and not resume:
        cleaned = clean_temporaries(out_dir)
        atomic_write_text(out_dir / "config.toml", config_to_toml(config))
    sense = driver.sense
    sgn = -1.0 if sense == "max" else 1.0  # fitness = sgn * cost
    reporter = Reporter(rc.generations, quiet=quiet, label=study.name)
    log = RunLog(out_dir / "log.txt" if out_dir is not None else None, reporter)
    columns = COLUMNS + tuple(driver.extra_columns)
    stats = StatsWriter(out_dir / "stats.csv", columns) if out_dir is not None \
        else MemoryStats(columns)
    history = HistoryWriter(out_dir / HISTORY_NAME) if out_dir is not None and rc.history_every \
        else None

    finish_only = False  # a resume that only writes the final artifacts
    if resume:
        state, rng, c, notes = restore(out_dir, driver, config)
        cleaned = clean_temporaries(out_dir)
        done = c.get("stop_reason")
        if done not in (None, "interrupted"):
            ended = driver.stop(state) is not None
            limit = limit_reached(config, c, driver.best(state)[1], sgn)
            raised = done in LIMIT_REASONS and limit is None and not ended  # a limit raised
            if c.get("finished") is False and not raised:
                finish_only = True  # stopped while writing the final artifacts
            elif ended or limit:
                raise InputError(f"{out_dir}: the run already finished ({done}); " + (
                    "it cannot be continued" if ended else
                    "raise its limit to continue, e.g. --set run.generations=N"))
        c["stop_reason"] = done if finish_only else None
        c.pop("finished", None)
        stats.truncate(c["stats_offset"])
        if history is not None:
            history.truncate(c.get("history_offset", 0))
        log.truncate(c["log_offset"])
        for line in notes:
            log(line)
        log(f"resumed at generation {c['generation']} to write the final artifacts (the "
            "run was stopped while writing them)" if finish_only else
            f"resumed at generation {c['generation']} with evaluator {rc.evaluator}")
    else:
        rng = np.random.default_rng(rc.seed)
        state = driver.init(rng)
        c = {"generation": -1, "evaluations": 0, "wall_s": 0.0, "failed_total": 0,
             "hist_best": [], "hist_mean": [], "best_metrics": {},
             "stats_offset": stats.offset, "log_offset": log.offset,
             "history_offset": history.offset if history is not None else 0}
        log(f"run {study.name} seed {rc.seed} evaluator {rc.evaluator} -> {out_dir or '-'}")
    _record_physics(problem, out_dir, resume, log)
    if stale_owner:
        log(f"note: took over the run folder's lock from {stale_owner}, which is no longer "
            "running")
    if out_dir is not None and cleaned:
        log(f"note: removed {cleaned} temporary file(s) left by an interrupted write")

    own_evaluator = evaluator is None  # a given evaluator is the caller's to close
    if own_evaluator:
        evaluator = SerialEvaluator(lambda _cfg: problem, None) \
            if rc.evaluator == "serial" or finish_only else \
            make_evaluator(rc.evaluator, study.make_problem, config.problem, rc.workers,
                           rc.chunks_per_worker, rc.address)

    def snapshot() -> tuple[dict, dict]:
        a, m = driver.state_arrays(state)
        meta = {"state." + k: v for k, v in m.items()}
        hist = history.offset if history is not None else 0
        meta.update(rng=rng_state(rng), counters=dict(c, stats_offset=stats.offset,
                                                       log_offset=log.offset,
                                                       history_offset=hist),
                    config=record)
        return {"state." + k: v for k, v in a.items()}, meta

    def context(reason: str | None = None) -> RunContext:
        bx, bc = driver.best(state)
        return RunContext(study.name, out_dir, config, problem, generation=c["generation"],
                          evaluations=c["evaluations"], best_genome=bx,
                          best_fitness=sgn * bc, best_metrics=dict(c["best_metrics"]),
                          stop_reason=reason, log=log, driver=driver, state=state)

    save = out_dir is not None
    record = config_record(config)
    snap = snapshot() if save else None  # Ctrl-C in the first step still leaves a checkpoint
    t_start = time.perf_counter() - c["wall_s"]
    reason = c["stop_reason"] if finish_only else None
    try:
        with sigterm_as_interrupt():
            while reason is None:
                t0 = time.perf_counter()
                state, rep = driver.step(state, rng, evaluator)
                c["evaluations"] += rep.evaluations
                c["generation"] += 1
                if rep.failed:
                    c["failed_total"] += rep.failed
                    first = rep.errors[0] if rep.errors else "non-finite fitness"
                    log(f"generation {c['generation']}: {rep.failed} individual(s) failed and "
                        f"got the worst fitness ({first})")
                for line in rep.lines:
                    log(f"generation {c['generation']}: {line}")
                if rep.best_metrics is not None:
                    c["best_metrics"] = rep.best_metrics
                _, best_cost = driver.best(state)
                ps = population_stats(sgn * np.asarray(rep.cost, float))
                dt = time.perf_counter() - t0
                c["wall_s"] = time.perf_counter() - t_start
                best_now = ps["max"] if sense == "max" else ps["min"]
                div = diversity(rep.population, problem.genome.span) \
                    if rep.population is not None else float("nan")
                row = {"generation": c["generation"], "evaluations": c["evaluations"],
                       "best": best_now, **ps, "best_so_far": sgn * best_cost,
                       "wall_s": round(c["wall_s"], 4),
                       "evals_per_s": round(rep.evaluations / dt, 2) if dt > 0 else float("nan"),
                       "diversity": div, "failed": rep.failed, **rep.extras}
                stats.write(row)
                loggers.row(row)
                if history is not None and rep.population is not None \
                        and c["generation"] % rc.history_every == 0:
                    history.write(c["generation"], rep.population, sgn * np.asarray(rep.cost))
                reporter.update(c["generation"], sgn * best_cost, ps["mean"], c["evaluations"])
                reason = stop_reason(driver, state, config, c, best_cost, ps["mean"] * sgn, sgn)
                c["stop_reason"] = reason
                every = rc.checkpoint_every
                due = reason is None and every and c["generation"] % every == 0
                if save and (driver.snapshot_every_step or due or reason is not None):
                    snap = snapshot()
                if save and due:
                    save_checkpoint(out_dir, c["generation"], *snap)
                    _write_archive(driver, state, out_dir)
                    _hook(study.on_checkpoint, context(), log)
    except KeyboardInterrupt:
        reason = "interrupted"
        if snap is not None:
            done = snap[1]["counters"].get("stop_reason")
            if done in (None, "interrupted"):
                snap[1]["counters"]["stop_reason"] = reason
            else:  # the run had ended: only its final artifacts are left for a resume
                snap[1]["counters"]["finished"] = False
    except Exception as e:
        if snap is not None:
            save_checkpoint(out_dir, max(snap[1]["counters"]["generation"], 0), *snap)
        log(f"run failed at generation {c['generation']}: {type(e).__name__}: {e}"
            + (f"; 'evomotion resume {out_dir}' continues from the last checkpoint"
               if snap is not None else ""))
        reporter.close()
        if own_evaluator:
            evaluator.close()
        driver.close()
        raise
    finally:
        reporter.close()
        loggers.close()
    if own_evaluator:
        evaluator.close()
    finishing = snap is not None and reason != "interrupted"
    if snap is not None:  # the finishing phase is resumable: the checkpoint says it is due
        if finishing:
            snap[1]["counters"]["finished"] = False
        save_checkpoint(out_dir, max(snap[1]["counters"]["generation"], 0), *snap)
    log(f"stopped: {reason} at generation {c['generation']} after {c['evaluations']} "
        f"evaluations")
    ctx = context(reason)
    code = EXIT_INTERRUPTED if reason == "interrupted" else 0
    if code == 0 and driver.uses_evaluator and not np.isfinite(ctx.best_fitness):
        log("no individual got a finite fitness (every evaluation failed or was NaN/inf); "
            "best.json holds null")
        code = EXIT_NO_FINITE
    if save:
        try:
            with sigterm_as_interrupt():
                code = _finish(study, driver, state, ctx, code, loggers, log)
        except KeyboardInterrupt:
            log("stopped while writing the final artifacts; 'evomotion resume "
                f"{out_dir}' writes them")
            driver.close()
            return RunResult(out_dir, "interrupted", c["generation"], c["evaluations"],
                             ctx.best_fitness, ctx.best_genome, ctx.best_metrics,
                             EXIT_INTERRUPTED, driver, state, [])
        if finishing:
            snap[1]["counters"]["finished"] = True
            save_checkpoint(out_dir, max(snap[1]["counters"]["generation"], 0), *snap)
    driver.close()
    return RunResult(out_dir, reason, c["generation"], c["evaluations"], ctx.best_fitness,
                     ctx.best_genome, ctx.best_metrics, code, driver, state,
                     getattr(stats, "rows", []))


def _finish(study: Any, driver: Driver, state: Any, ctx: RunContext, code: int, loggers,
            log) -> int:
    """The final artifacts (best.json, plots, the archive, the study's own); each is written
    atomically and all of them again by a resume when a run stops before it is done. A file
    that cannot be written (a full disk) ends the run with its one-line error, unfinished."""
    out_dir = ctx.out_dir
    _write_best(study, ctx, driver.sense, ctx.config.run.seed, log)
    if ctx.generation >= 0:
        from evomotion.run.plots import plot_fitness  # matplotlib: only when plotting

        plot_fitness(out_dir / "stats.csv", out_dir / "plots" / "fitness", title=study.name)
        if _write_archive(driver, state, out_dir):
            from evomotion.run.plots import plot_archive, plot_qd

            plot_qd(out_dir / "stats.csv", out_dir / "plots" / "qd", title=study.name)
            plot_archive(out_dir / "archive.npz", out_dir / "plots" / "archive")
    if code != EXIT_NO_FINITE:
        _hook(study.on_checkpoint, ctx, log)
    if code == 0:  # a second Ctrl-C should not wait for videos
        code = _hook(study.finalize, ctx, log) or 0
    loggers.finish(ctx)  # after the study's artifacts (best.motion)
    return code


def _write_archive(driver: Any, state: Any, out_dir: Path) -> bool:
    """``archive.npz`` of a quality-diversity run (:mod:`evomotion.run.archive_file`)."""
    view = driver.archive_view(state)
    if view is None:
        return False
    from evomotion.run.archive_file import NAME, write_archive

    write_archive(out_dir / NAME, *view)
    return True


#: physics.json's robot keys: a run folder written before the NAO was recorded lacks them
ROBOT_KEYS = ("robot", "robot_spec_sha256", "robot_mjcf_sha256")


def _hook(fn, ctx: RunContext, log) -> Any:
    if fn is None:
        return None
    run_cfg = getattr(ctx.config, "run", None)
    off = None if getattr(run_cfg, "videos", True) else "videos are off (run.videos = false)"
    try:
        if off is None:
            return fn(ctx)
        from evomotion.sim.render import videos_off

        with videos_off(off):
            return fn(ctx)
    except WriteError:
        raise  # a full or read-only disk: the run ends unfinished, a resume completes it
    except Exception as e:  # noqa: BLE001 - an artifact failure must not lose the run
        log(f"warning: {getattr(fn, '__name__', 'hook')} failed: {type(e).__name__}: {e}")
        return None


def _write_best(study: Any, ctx: RunContext, sense: str, seed: int, log) -> None:
    """``best.json``: the envelope (study, sense, fitness, genome, metrics), the study's keys,
    then generation, evaluations, stop_reason and seed."""
    rec: dict[str, Any] = {"study": ctx.study, "sense": sense, "fitness": ctx.best_fitness,
                           "genome": ctx.best_genome, "metrics": ctx.best_metrics}
    extra = _hook(getattr(study, "best_record", None), ctx, log) or {}
    rec.update({k: v for k, v in extra.items() if k not in rec})
    rec.update(generation=ctx.generation, evaluations=ctx.evaluations,
               stop_reason=ctx.stop_reason, seed=seed)
    write_json(ctx.out_dir / "best.json", rec)


def _record_physics(problem: Any, out_dir: Path | None, resume: bool, log) -> None:
    """``physics.json``: the problem's physics backend and what it guarantees (MuJoCo
    studies); a non-CPU backend is logged, and a resume on other physics is noted."""
    fn = getattr(problem, "physics_record", None)
    if not callable(fn):
        return
    now = fn()
    if now.get("backend") != "cpu":
        log(f"physics: backend {now['backend']} on {now.get('device', '?')}, "
            f"{now.get('precision', '?')}; {now.get('guarantee', '')}")
    if out_dir is None:
        return
    path = out_dir / PHYSICS_NAME
    if resume and path.exists():
        try:
            before = read_json(path, PHYSICS_NAME, 1 << 20, finite=False)
        except InputError:
            before = None
        keys = ("backend", "device", "precision", "mujoco", "mujoco_warp", "deterministic",
                "robot", "robot_spec_sha256", "robot_mjcf_sha256")
        if isinstance(before, dict):  # a key a run folder's record lacks was not recorded
            keys = tuple(k for k in keys if k in before or k not in ROBOT_KEYS)
        if isinstance(before, dict) and any(before.get(k) != now.get(k) for k in keys):
            log(f"note: resumed on other physics than the run started on ({PHYSICS_NAME}: "
                f"{ {k: before.get(k) for k in keys if before.get(k) != now.get(k)} } -> "
                f"{ {k: now.get(k) for k in keys if before.get(k) != now.get(k)} }); the "
                "result is not bit-identical to an uninterrupted run")
    atomic_write_text(path, json.dumps(now, indent=1) + "\n")
