"""The run loop: every study runs here, through a :class:`~evomotion.run.driver.Driver`.

The runner owns the run folder (lock, config, log), the evaluator and the finishing phase;
the driver owns the method; the step loop (:mod:`evomotion.run.loop`) announces every step to
the run's subscribers (:mod:`evomotion.run.recorders`: stats, history, console, checkpoints,
loggers; :mod:`evomotion.run.artifacts`: best.json, plots, the archive, the study's hooks).
Bit-identical resume: after every step the checkpoint writer keeps a snapshot of the driver
state, the RNG state and the files' offsets (drivers whose state is too large to copy every
step are snapshotted at checkpoints only). Checkpoints (every ``run.checkpoint_every`` steps,
at the end, and on Ctrl-C/SIGTERM or a crash) write that snapshot, so a resumed run replays
exactly the steps that were lost. The finishing phase is resumable: the last checkpoint says
``counters.finished = false`` until every final artifact is written.

With ``out_dir=None`` the same loop runs without a folder (no files, no console): the
experiments of the studies use that for their many short runs.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast

import numpy as np

from evomotion.errors import InputError
from evomotion.outfile import atomic_write_text
from evomotion.run import loop
from evomotion.run.artifacts import (
    EXIT_NO_FINITE,
    ArchiveWriter,
    BestWriter,
    PlotWriter,
    StudyArtifacts,
)
from evomotion.run.ask_tell import AskTellDriver, make_optimizer
from evomotion.run.config import Config, config_to_toml
from evomotion.run.console import Reporter
from evomotion.run.context import RunContext
from evomotion.run.contracts import LoopStudy, RunStudy, SeededByRun, Subscriber
from evomotion.run.counters import Counters
from evomotion.run.driver import Driver
from evomotion.run.evaluators import SerialEvaluator, make_evaluator
from evomotion.run.folder import (
    check_new_run,
    check_resumable,
    clean_temporaries,
    prepare_new_run,
)
from evomotion.run.history import NAME as HISTORY_NAME
from evomotion.run.history import HistoryWriter
from evomotion.run.limits import check_memory
from evomotion.run.lock import RunLock
from evomotion.run.loggers import Loggers, check_loggers, make_loggers
from evomotion.run.recorders import (
    CheckpointWriter,
    ConsoleRecorder,
    HistoryRecorder,
    LoggerRelay,
    StatsRecorder,
)
from evomotion.run.resume import config_record, resume_run
from evomotion.run.run_record import record_run
from evomotion.run.run_state import RunFiles, RunState
from evomotion.run.runlog import RunLog, sigterm_as_interrupt
from evomotion.run.stats import COLUMNS, MemoryStats, StatsWriter

EXIT_INTERRUPTED = 130


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


def build_driver(study: LoopStudy, config: Config, problem: Any) -> Driver:
    """The study's own driver for ``algorithm.name`` if it has one, else the ask/tell one."""
    own = study.algorithms.get(config.algorithm.name)
    if own is not None:
        return own[1](problem, config)
    return AskTellDriver(problem, make_optimizer(problem, config.algorithm))


def run_study(study: LoopStudy, config: Config, out_dir: Path | str | None = None,
              quiet: bool = False, resume: bool = False, problem: Any = None,
              evaluator: Any = None, overwrite: bool = False,
              subscribers: Sequence[Subscriber] = ()) -> RunResult:
    """Run (or resume, when ``resume``) ``study`` with ``config`` in ``out_dir``.

    ``problem`` (default: built from ``config.problem``) and ``evaluator`` (default: the one
    ``run.evaluator`` names; a given one is not closed here) serve callers that run many
    short runs on one problem. The run folder is locked while the run writes to it; a new run
    into a folder that already holds one is refused unless ``overwrite``. ``subscribers``
    (:class:`~evomotion.run.contracts.Subscriber`) hear every event of the loop after the
    run's own (stats, history, console, checkpoints, artifacts, loggers)."""
    if out_dir is None:
        if resume:
            raise InputError("resume needs a run folder")
        return _run(study, config, None, True, False, problem, evaluator, None, subscribers)
    out_dir = Path(out_dir)
    prepared = None
    started = False
    try:
        if resume:
            check_resumable(out_dir)  # before anything is made or removed in the folder
        else:
            check_new_run(out_dir, overwrite)  # refused before the lock file is made
            # a config the problem refuses is refused before the folder is made or emptied
            with sigterm_as_interrupt():
                prepared = _prepare(study, config, problem)
                prepared[2].check_new_run()  # e.g. the policy a search starts from
                check_loggers(config.run.loggers)  # a missing package: before emptying
        out_dir.mkdir(parents=True, exist_ok=True)
        # SIGTERM is Ctrl-C from the moment the lock names this process (a stop from the
        # studio during the set-up ends the run cleanly, not by the signal's default)
        with sigterm_as_interrupt(), RunLock(out_dir) as lock:
            if not resume:
                prepare_new_run(out_dir, study.name, overwrite)
            started = True
            return _run(study, config, out_dir, quiet, resume, problem, evaluator,
                        lock.stale_owner, subscribers, prepared)
    except BaseException:
        if prepared is not None and not started:  # refused (a lock, a logger): release it
            prepared[2].close()
        raise


def _run(study: LoopStudy, config: Config, out_dir: Path | None, quiet: bool, resume: bool,
         problem: Any, evaluator: Any, stale_owner: str | None = None,
         extra: Sequence[Subscriber] = (),
         prepared: tuple[Config, Any, Driver] | None = None) -> RunResult:
    hooks = _hooks(study) if out_dir is not None else None
    config, problem, driver = prepared or _prepare(study, config, problem)
    rc = config.run
    loggers = make_loggers(rc.loggers, out_dir, hooks.replay) \
        if hooks is not None and out_dir is not None else Loggers([])  # before any file
    cleaned = 0
    if out_dir is not None and not resume:
        cleaned = clean_temporaries(out_dir)
        atomic_write_text(out_dir / "config.toml", config_to_toml(config))
    reporter = Reporter(rc.generations, quiet=quiet, label=study.name)
    log = RunLog(out_dir / "log.txt" if out_dir is not None else None, reporter)
    columns = COLUMNS + tuple(driver.extra_columns)
    stats: StatsWriter | MemoryStats = StatsWriter(out_dir / "stats.csv", columns) \
        if out_dir is not None else MemoryStats(columns)
    history = HistoryWriter(out_dir / HISTORY_NAME) if out_dir is not None and rc.history_every \
        else None
    files = RunFiles(stats, history, log)
    if resume:
        assert out_dir is not None
        run, finish_only, cleaned = resume_run(study, config, problem, driver, out_dir, files)
    else:
        rng = np.random.default_rng(rc.seed)
        counters = Counters(stats_offset=stats.offset, log_offset=log.offset,
                            history_offset=history.offset if history is not None else 0)
        run = RunState(study, config, problem, driver, driver.init(rng), rng, counters, log,
                       out_dir)
        finish_only = False
        log(f"run {study.name} seed {rc.seed} evaluator {rc.evaluator} -> {out_dir or '-'}")
    if hooks is not None and out_dir is not None:
        record_run(hooks, problem, out_dir, resume, log)
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
    checkpoints = CheckpointWriter(out_dir, config_record(config), files.offsets) \
        if out_dir is not None else None
    subscribers = [*_subscribers(hooks, run, files, reporter, loggers, checkpoints), *extra]
    reason = _drive(run, subscribers, checkpoints, evaluator, own_evaluator)
    return _conclude(run, subscribers, checkpoints, reason, stats)


def _hooks(study: LoopStudy) -> RunStudy:
    """``study`` as a study with artifact hooks (every run with a folder needs one)."""
    if not isinstance(study, RunStudy):
        raise TypeError(f"study {study.name!r}: a run with a folder needs a study with the "
                        "artifact hooks of evomotion.run.contracts.RunStudy")
    return study


def _prepare(study: LoopStudy, config: Config, problem: Any) -> tuple[Config, Any, Driver]:
    """The config (problem randomness drawn from the run seed), the problem and the driver,
    checked before any population array is allocated."""
    rc = config.run
    if isinstance(config.problem, SeededByRun):  # e.g. perturbed worlds from the run seed
        config = dataclasses.replace(config, problem=config.problem.with_run_seed(rc.seed))
    problem = problem if problem is not None else study.make_problem(config.problem)
    check_memory(study, config, problem)  # before any population array is allocated
    driver = build_driver(study, config, problem)
    if rc.evaluator != "serial" and not driver.uses_evaluator:
        raise InputError(f"run.evaluator: study {study.name!r} has no batch evaluation to "
                         f"distribute; use 'serial', got {rc.evaluator!r}")
    return config, problem, driver


def _subscribers(study: RunStudy | None, run: RunState, files: RunFiles, reporter: Reporter,
                 loggers: Loggers, checkpoints: CheckpointWriter | None) -> list[Subscriber]:
    """The loop's subscribers, in the order they hear every event."""
    subs: list[Subscriber] = [StatsRecorder(files.stats)]
    if files.history is not None:
        subs.append(HistoryRecorder(files.history, run.config.run.history_every))
    subs.append(ConsoleRecorder(reporter))
    if checkpoints is not None and study is not None:
        scope = study.artifact_scope
        subs += [checkpoints, BestWriter(study.best_record, run.driver.sense, scope),
                 PlotWriter(study.name), ArchiveWriter(study.name),
                 StudyArtifacts(study.on_checkpoint, study.finalize, scope)]
    subs.append(LoggerRelay(loggers))  # its files after the study's (best.motion)
    return subs


def _drive(run: RunState, subscribers: list[Subscriber], checkpoints: CheckpointWriter | None,
           evaluator: Any, own_evaluator: bool) -> str:
    """The step loop to its end; Ctrl-C or SIGTERM is the reason ``interrupted``, a crash
    leaves the last snapshot as a checkpoint and is raised."""
    loop.start(run, subscribers)
    closed = False
    try:
        with sigterm_as_interrupt():
            reason = loop.run_steps(run, subscribers, evaluator)
    except KeyboardInterrupt:
        reason = "interrupted"
        if checkpoints is not None:
            checkpoints.interrupted()
    except Exception as e:
        if checkpoints is not None:
            checkpoints.save()
        run.log(f"run failed at generation {run.counters.generation}: {type(e).__name__}: {e}"
                + (f"; 'evomotion resume {run.out_dir}' continues from the last checkpoint"
                   if checkpoints is not None else ""))
        closed = True
        loop.close(run, subscribers)
        if own_evaluator:
            evaluator.close()
        run.driver.close()
        raise
    finally:
        if not closed:
            loop.close(run, subscribers)
    if own_evaluator:
        evaluator.close()
    return reason


def _conclude(run: RunState, subscribers: list[Subscriber],
              checkpoints: CheckpointWriter | None, reason: str,
              stats: StatsWriter | MemoryStats) -> RunResult:
    """After the loop: the checkpoint saying whether the final artifacts are due, then the
    finishing phase (resumable: a Ctrl-C or a kill in it leaves them due)."""
    c, log, driver = run.counters, run.log, run.driver
    finishing = checkpoints is not None and reason != "interrupted"
    if checkpoints is not None:  # the finishing phase is resumable: the checkpoint says so
        if finishing:
            checkpoints.counters["finished"] = False
        checkpoints.save()
    log(f"stopped: {reason} at generation {c.generation} after {c.evaluations} evaluations")
    ctx = run.context(reason)
    code = EXIT_INTERRUPTED if reason == "interrupted" else 0
    if code == 0 and driver.uses_evaluator and not np.isfinite(ctx.best_fitness):
        log("no individual got a finite fitness (every evaluation failed or was NaN/inf); "
            "best.json holds null")
        code = EXIT_NO_FINITE
    if checkpoints is not None:
        try:
            with sigterm_as_interrupt():
                code = _finish(subscribers, ctx, code)
        except KeyboardInterrupt:
            log("stopped while writing the final artifacts; 'evomotion resume "
                f"{run.out_dir}' writes them")
            driver.close()
            return RunResult(run.out_dir, "interrupted", c.generation, c.evaluations,
                             ctx.best_fitness, _genome(ctx), ctx.best_metrics,
                             EXIT_INTERRUPTED, driver, run.state, [])
        if finishing:
            checkpoints.counters["finished"] = True
            checkpoints.save(arrays=False)  # the arrays are those saved before finishing
    driver.close()
    rows = stats.rows if isinstance(stats, MemoryStats) else []
    return RunResult(run.out_dir, reason, c.generation, c.evaluations, ctx.best_fitness,
                     _genome(ctx), ctx.best_metrics, code, driver, run.state, rows)


def _genome(ctx: RunContext) -> np.ndarray:
    """The best genome (the driver's :meth:`~evomotion.run.driver.Driver.best`: never None)."""
    return cast(np.ndarray, ctx.best_genome)


def _finish(subscribers: list[Subscriber], ctx: RunContext, code: int) -> int:
    """The finishing phase (:func:`evomotion.run.loop.finish`): best.json, plots, the
    archive, the study's artifacts, the loggers' files. A file that cannot be written (a full
    disk) ends the run with its one-line error, unfinished; a resume writes them all again."""
    return loop.finish(subscribers, ctx, code)
