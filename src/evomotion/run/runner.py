"""The generic ask/tell run loop: evaluation, statistics, stopping, checkpoints, resume.

Bit-identical resume: after every generation the runner keeps an in-memory snapshot of the
optimizer state, the RNG state and the logger offsets. Checkpoints (every
``run.checkpoint_every`` generations, at the end, and on Ctrl-C/SIGTERM or a crash) write
that snapshot, so a resumed run replays exactly the generations that were lost.
"""

from __future__ import annotations

import signal
import threading
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.core.algorithms import ALGORITHMS
from evomotion.core.problem import to_cost
from evomotion.core.state import rng_from_state, rng_state, state_from_arrays, state_to_arrays
from evomotion.errors import InputError
from evomotion.run.checkpoint import load_checkpoint, save_checkpoint
from evomotion.run.config import Config, config_to_toml
from evomotion.run.console import Reporter
from evomotion.run.context import RunContext
from evomotion.run.evaluators import SerialEvaluator, make_evaluator
from evomotion.run.folder import atomic_write_text, write_json
from evomotion.run.plots import plot_fitness
from evomotion.run.stats import StatsWriter, diversity, population_stats

EXIT_INTERRUPTED = 130


@dataclass
class RunResult:
    out_dir: Path
    stop_reason: str
    generation: int
    evaluations: int
    best_fitness: float
    best_genome: np.ndarray
    best_metrics: dict[str, float] = field(default_factory=dict)
    exit_code: int = 0


class RunLog:
    """``log.txt`` in the run folder, mirrored to the console reporter."""

    def __init__(self, path: Path, reporter: Reporter | None = None) -> None:
        self.path = path
        self.path.touch()
        self.reporter = reporter

    @property
    def offset(self) -> int:
        return self.path.stat().st_size

    def truncate(self, offset: int) -> None:
        with open(self.path, "r+b") as fh:
            fh.truncate(offset)

    def __call__(self, msg: str) -> None:
        with open(self.path, "a") as fh:
            fh.write(msg.rstrip("\n") + "\n")
        if self.reporter is not None:
            self.reporter.line(msg)


@contextmanager
def _sigterm_as_interrupt():
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        raise KeyboardInterrupt

    old = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def run_study(study: Any, config: Config, out_dir: Path, quiet: bool = False,
              resume: bool = False) -> RunResult:
    """Run (or resume, when ``resume``) the generic loop of ``study`` in ``out_dir``."""
    out_dir = Path(out_dir)
    if not resume:
        atomic_write_text(out_dir / "config.toml", config_to_toml(config))
    rc = config.run
    problem = study.make_problem(config.problem)
    sense = problem.sense
    _, factory = ALGORITHMS[config.algorithm.name]
    opt = factory(problem.genome, config.algorithm)
    reporter = Reporter(rc.generations, quiet=quiet, label=study.name)
    log = RunLog(out_dir / "log.txt", reporter)
    stats = StatsWriter(out_dir / "stats.csv")
    sgn = -1.0 if sense == "max" else 1.0  # fitness = sgn * cost

    if resume:
        arrays, meta = load_checkpoint(out_dir)
        state_cls = type(opt.init(np.random.default_rng(0)))
        st_arrays = {k[6:]: v for k, v in arrays.items() if k.startswith("state.")}
        st_meta = {k[6:]: v for k, v in meta.items() if k.startswith("state.")}
        state = state_from_arrays(state_cls, st_arrays, st_meta)
        rng = rng_from_state(meta["rng"])
        c = meta["counters"]
        done = c.get("stop_reason")
        if done not in (None, "interrupted") and _limit_reached(config, c, opt.best(state)[1],
                                                               sgn):
            raise InputError(f"{out_dir}: the run already finished ({done}); raise its limit "
                             "to continue, e.g. --set run.generations=N")
        c["stop_reason"] = None
        stats.truncate(c["stats_offset"])
        log.truncate(c["log_offset"])
        log(f"resumed at generation {c['generation']} with evaluator {rc.evaluator}")
    else:
        rng = np.random.default_rng(rc.seed)
        state = opt.init(rng)
        c = {"generation": -1, "evaluations": 0, "wall_s": 0.0, "failed_total": 0,
             "hist_best": [], "hist_mean": [], "best_metrics": {},
             "stats_offset": stats.offset, "log_offset": log.offset}
        log(f"run {study.name} seed {rc.seed} evaluator {rc.evaluator} -> {out_dir}")

    if rc.evaluator == "serial":
        evaluator = SerialEvaluator(lambda _cfg: problem, None)
    else:
        evaluator = make_evaluator(rc.evaluator, study.make_problem, config.problem,
                                   rc.workers, rc.chunks_per_worker, rc.address)

    def snapshot() -> tuple[dict, dict]:
        a, m = state_to_arrays(state)
        arrays = {"state." + k: np.array(v, copy=True) for k, v in a.items()}
        meta = {"state." + k: v for k, v in m.items()}
        meta.update(rng=rng_state(rng), counters=dict(c, stats_offset=stats.offset,
                                                       log_offset=log.offset))
        return arrays, meta

    def context(reason: str | None = None) -> RunContext:
        bx, bc = opt.best(state)
        return RunContext(study.name, out_dir, config, problem, generation=c["generation"],
                          evaluations=c["evaluations"], best_genome=bx,
                          best_fitness=sgn * bc, best_metrics=dict(c["best_metrics"]),
                          stop_reason=reason, log=log)

    snap = snapshot() if resume else None
    t_start = time.perf_counter() - c["wall_s"]
    reason = None
    try:
        with _sigterm_as_interrupt():
            while reason is None:
                t0 = time.perf_counter()
                genomes, state = opt.ask(state, rng)
                ev = evaluator(genomes)
                cost = to_cost(ev.fitness, sense)
                _, prev_best = opt.best(state)
                state = opt.tell(state, genomes, cost, rng)
                n = len(genomes)
                c["evaluations"] += n
                c["generation"] += 1
                nfail = int(ev.failed.sum()) if ev.failed is not None else 0
                if nfail:
                    c["failed_total"] += nfail
                    first = ev.errors[0] if ev.errors else "non-finite fitness"
                    log(f"generation {c['generation']}: {nfail} individual(s) failed and got "
                        f"the worst fitness ({first})")
                i = int(np.argmin(cost))
                if cost[i] < prev_best:
                    c["best_metrics"] = {k: float(np.asarray(v[i]).ravel()[0])
                                         for k, v in ev.metrics.items() if np.ndim(v[i]) <= 1
                                         and np.size(v[i]) == 1}
                _, best_cost = opt.best(state)
                pop, pcost = opt.population(state)
                fit = sgn * np.asarray(pcost, float)
                ps = population_stats(fit)
                dt = time.perf_counter() - t0
                c["wall_s"] = time.perf_counter() - t_start
                best_now = ps["max"] if sense == "max" else ps["min"]
                stats.write({"generation": c["generation"], "evaluations": c["evaluations"],
                             "best": best_now, **ps, "best_so_far": sgn * best_cost,
                             "wall_s": round(c["wall_s"], 4),
                             "evals_per_s": round(n / dt, 2) if dt > 0 else float("nan"),
                             "diversity": diversity(pop, problem.genome.span),
                             "failed": nfail})
                reporter.update(c["generation"], sgn * best_cost, ps["mean"], c["evaluations"])
                reason = _stop_reason(opt, state, config, c, best_cost, ps["mean"] * sgn, sgn)
                c["stop_reason"] = reason
                snap = snapshot()
                every = rc.checkpoint_every
                if reason is None and every and c["generation"] % every == 0:
                    save_checkpoint(out_dir, c["generation"], *snap)
                    _hook(study.on_checkpoint, context(), log)
    except KeyboardInterrupt:
        reason = "interrupted"
        if snap is not None:
            snap[1]["counters"]["stop_reason"] = reason
    except Exception as e:
        if snap is not None:
            save_checkpoint(out_dir, max(c["generation"], 0), *snap)
        log(f"run failed at generation {c['generation']}: {type(e).__name__}: {e}; "
            f"'evomotion resume {out_dir}' continues from the last checkpoint")
        reporter.close()
        evaluator.close()
        raise
    finally:
        reporter.close()
    evaluator.close()
    if snap is not None:
        save_checkpoint(out_dir, max(c["generation"], 0), *snap)
    log(f"stopped: {reason} at generation {c['generation']} after {c['evaluations']} "
        f"evaluations")
    ctx = context(reason)
    _write_best(ctx, sense, rc.seed)
    if c["generation"] >= 0:
        plot_fitness(out_dir / "stats.csv", out_dir / "plots" / "fitness", title=study.name)
    _hook(study.on_checkpoint, ctx, log)
    if reason != "interrupted":  # a second Ctrl-C should not wait for videos
        _hook(study.finalize, ctx, log)
    return RunResult(out_dir, reason, c["generation"], c["evaluations"], ctx.best_fitness,
                     ctx.best_genome, ctx.best_metrics,
                     EXIT_INTERRUPTED if reason == "interrupted" else 0)


def _stop_reason(opt, state, config: Config, c: dict, best_cost: float, mean_cost: float,
                 sgn: float) -> str | None:
    """The first stopping rule that fires (costs are minimised; ``fitness = sgn * cost``)."""
    rc = config.run
    limit = _limit_reached(config, c, best_cost, sgn)
    if limit is not None:
        return limit
    if rc.stagnation_generations:
        n = rc.stagnation_generations
        c["hist_best"] = (c["hist_best"] + [best_cost])[-(n + 1):]
        c["hist_mean"] = (c["hist_mean"] + [mean_cost])[-(n + 1):]
        if len(c["hist_best"]) == n + 1:
            db = c["hist_best"][0] - c["hist_best"][-1]
            dm = c["hist_mean"][0] - c["hist_mean"][-1]
            if db < rc.stagnation_eps and dm < rc.stagnation_eps:
                return "stagnation"
    return opt.stop(state)


def _limit_reached(config: Config, c: dict, best_cost: float, sgn: float) -> str | None:
    rc = config.run
    if c["generation"] >= rc.generations:
        return "generations"
    if rc.max_evaluations and c["evaluations"] >= rc.max_evaluations:
        return "max_evaluations"
    if rc.target is not None and best_cost <= sgn * rc.target:
        return "target"
    if rc.wall_seconds and c["wall_s"] >= rc.wall_seconds:
        return "wall_seconds"
    return None


def _hook(fn, ctx: RunContext, log) -> None:
    if fn is None:
        return
    try:
        fn(ctx)
    except Exception as e:  # noqa: BLE001 - an artifact failure must not lose the run
        log(f"warning: {getattr(fn, '__name__', 'hook')} failed: {type(e).__name__}: {e}")


def _write_best(ctx: RunContext, sense: str, seed: int) -> None:
    write_json(ctx.out_dir / "best.json", {
        "study": ctx.study, "sense": sense, "fitness": ctx.best_fitness,
        "genome": ctx.best_genome, "metrics": ctx.best_metrics, "generation": ctx.generation,
        "evaluations": ctx.evaluations, "stop_reason": ctx.stop_reason, "seed": seed})
