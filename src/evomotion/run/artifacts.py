"""The run loop's artifact subscribers: best.json, plots, the QD archive, the study's hooks.

They write at checkpoints (the archive, the study's ``on_checkpoint``) and in the finishing
phase (``on_finish``), in this order: ``best.json``, the fitness plots, ``archive.npz`` and its
plots, the study's ``on_checkpoint`` then ``finalize``. Each file is written atomically, and
all of them again by a resume when a run stops before it is done. A file that cannot be
written (:class:`~evomotion.outfile.WriteError`: a full disk) ends the run with its one-line
error, unfinished; any other failure of a study's hook is a warning in the run log.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from evomotion.outfile import WriteError, write_json
from evomotion.run.context import RunContext
from evomotion.run.contracts import ArtifactScope, Subscriber
from evomotion.run.run_state import RunState

EXIT_NO_FINITE = 5  # the run ended without any finite fitness


def call_hook(fn: Callable[[RunContext], Any] | None, ctx: RunContext,
              scope: ArtifactScope | None = None) -> Any:
    """``fn(ctx)`` (``None`` when there is no hook), inside the study's ``scope(ctx)`` when it
    has one; a failure other than a write error is logged as a warning and gives ``None``."""
    if fn is None:
        return None
    try:
        if scope is None:
            return fn(ctx)
        with scope(ctx):
            return fn(ctx)
    except WriteError:
        raise  # a full or read-only disk: the run ends unfinished, a resume completes it
    except Exception as e:  # noqa: BLE001 - an artifact failure must not lose the run
        ctx.log(f"warning: {getattr(fn, '__name__', 'hook')} failed: {type(e).__name__}: {e}")
        return None


class BestWriter(Subscriber):
    """``best.json``: the envelope (study, sense, fitness, genome, metrics), the study's keys
    (its ``best_record`` hook), then generation, evaluations, stop_reason and seed."""

    def __init__(self, best_record: Callable[[RunContext], dict[str, Any]] | None,
                 sense: str, scope: ArtifactScope | None = None) -> None:
        self.best_record, self.sense, self.scope = best_record, sense, scope

    def on_finish(self, ctx: RunContext, code: int) -> int:
        assert ctx.out_dir is not None
        rec: dict[str, Any] = {"study": ctx.study, "sense": self.sense,
                               "fitness": ctx.best_fitness, "genome": ctx.best_genome,
                               "metrics": ctx.best_metrics}
        extra = call_hook(self.best_record, ctx, self.scope) or {}
        rec.update({k: v for k, v in extra.items() if k not in rec})
        rec.update(generation=ctx.generation, evaluations=ctx.evaluations,
                   stop_reason=ctx.stop_reason, seed=ctx.config.run.seed)
        write_json(ctx.out_dir / "best.json", rec)
        return code


class PlotWriter(Subscriber):
    """``plots/fitness.*`` from stats.csv, once the run has taken a step."""

    def __init__(self, title: str) -> None:
        self.title = title

    def on_finish(self, ctx: RunContext, code: int) -> int:
        assert ctx.out_dir is not None
        if ctx.generation >= 0:
            from evomotion.run.plots import plot_fitness  # matplotlib: only when plotting

            plot_fitness(ctx.out_dir / "stats.csv", ctx.out_dir / "plots" / "fitness",
                         title=self.title)
        return code


class ArchiveWriter(Subscriber):
    """``archive.npz`` of a quality-diversity run (:mod:`evomotion.run.archive_file`) at
    every checkpoint and at the end, with its plots (``plots/qd.*``, ``plots/archive.*``)."""

    def __init__(self, title: str) -> None:
        self.title = title

    @staticmethod
    def write(driver: Any, state: Any, ctx_dir: Any) -> bool:
        view = driver.archive_view(state)
        if view is None:
            return False
        from evomotion.run.archive_file import NAME, write_archive

        write_archive(ctx_dir / NAME, *view)
        return True

    def on_checkpoint(self, run: RunState) -> None:
        self.write(run.driver, run.state, run.out_dir)

    def on_finish(self, ctx: RunContext, code: int) -> int:
        out = ctx.out_dir
        assert out is not None
        if ctx.generation >= 0 and self.write(ctx.driver, ctx.state, out):
            from evomotion.run.plots import plot_archive, plot_qd

            plot_qd(out / "stats.csv", out / "plots" / "qd", title=self.title)
            plot_archive(out / "archive.npz", out / "plots" / "archive")
        return code


class StudyArtifacts(Subscriber):
    """The study's ``on_checkpoint`` (every checkpoint and at the end, unless no fitness was
    finite) and ``finalize`` (once, at the end of a run that ended well; it may return an exit
    code)."""

    def __init__(self, on_checkpoint: Callable[[RunContext], Any] | None,
                 finalize: Callable[[RunContext], int | None] | None,
                 scope: ArtifactScope | None = None) -> None:
        self.checkpoint_hook, self.finalize, self.scope = on_checkpoint, finalize, scope

    def _call(self, fn: Callable[[RunContext], Any] | None, ctx: RunContext) -> Any:
        return call_hook(fn, ctx, self.scope)

    def on_checkpoint(self, run: RunState) -> None:
        self._call(self.checkpoint_hook, run.context())

    def on_finish(self, ctx: RunContext, code: int) -> int:
        if code != EXIT_NO_FINITE:
            self._call(self.checkpoint_hook, ctx)
        if code == 0:  # a second Ctrl-C should not wait for videos
            code = self._call(self.finalize, ctx) or 0
        return code

