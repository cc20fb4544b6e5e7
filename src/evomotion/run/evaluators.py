"""Evaluators: the seam between an optimizer's batch and the machines that evaluate it.

All evaluators return the same :class:`~evomotion.core.problem.Evaluation` for the same
genomes, in submission order, because problems are deterministic functions of each genome.
``serial`` evaluates the batch in-process; ``process`` splits it into chunks (a few per
worker, never one task per individual) sent to spawned worker processes that build the
problem once and survive each other's crashes (see :class:`ProcessEvaluator`). ``ray`` and
``dask`` are optional extras registered here lazily.
"""

from __future__ import annotations

import contextlib
import ctypes
import importlib
import itertools
import logging
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator
from multiprocessing.connection import wait as wait_ready
from typing import Any

import numpy as np

from evomotion.core.problem import Evaluation, Problem, Sense, failed_evaluation, sanitize
from evomotion.core.registry import lookup
from evomotion.errors import ClusterError
from evomotion.run.contracts import ConfigForWorker

WORKER_ENV = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}

log = logging.getLogger("evomotion.run.process")


def worker_config(problem_cfg: Any) -> Any:
    """The problem config a one-core worker builds from (process, Ray and Dask workers).

    The workers already fill every core, one per core, so a problem that would otherwise use
    several threads (e.g. ``mujoco.rollout`` threads left at 0 = all cores) says how to run on
    one: a problem config with a ``for_worker()`` method returns the config a one-core worker
    should build; any other config is used unchanged.
    """
    return problem_cfg.for_worker() if isinstance(problem_cfg, ConfigForWorker) else problem_cfg


def evaluate_safely(problem: Problem, genomes: np.ndarray) -> Evaluation:
    """Evaluate a batch; an exception isolates the failing individuals one by one.

    NaN/inf fitness and individuals whose evaluation raised get the worst fitness and are
    flagged in ``failed``; exception messages are kept in ``errors``. Never raises for a
    problem-side error.
    """
    n = genomes.shape[0]
    try:
        return sanitize(problem.evaluate(genomes), problem.sense, n)
    except Exception as batch_error:  # noqa: BLE001 - isolate per individual below
        if n == 1:
            ev = failed_evaluation(1, problem.sense, problem.metric_names)
            ev.errors.append(f"{type(batch_error).__name__}: {batch_error}")
            return ev
    parts = [evaluate_safely(problem, genomes[i:i + 1]) for i in range(n)]
    return Evaluation.concat(parts)


def split_chunks(n: int, n_chunks: int) -> list[slice]:
    """Contiguous slices covering ``range(n)`` in at most ``n_chunks`` nearly equal parts."""
    n_chunks = max(1, min(n_chunks, n))
    edges = np.linspace(0, n, n_chunks + 1).round().astype(int)
    return [slice(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:], strict=True) if b > a]


class SerialEvaluator:
    """Evaluate in this process."""

    name = "serial"

    def __init__(self, make_problem: Callable[[Any], Problem], problem_cfg: Any,
                 workers: int = 0, chunks_per_worker: int = 4, address: str = "") -> None:
        self.problem = make_problem(problem_cfg)

    def __call__(self, genomes: np.ndarray) -> Evaluation:
        return evaluate_safely(self.problem, genomes)

    def close(self) -> None:
        pass


# -- process workers ---------------------------------------------------------------------------

_PR_SET_PDEATHSIG = 1  # <linux/prctl.h>


def _watch_parent(parent_pid: int, poll_s: float = 0.5) -> None:
    while os.getppid() == parent_pid:
        time.sleep(poll_s)
    os._exit(1)


def _die_with_parent(parent_pid: int, use_prctl: bool = True) -> str:
    """Make this worker end when its parent does; returns how (``prctl`` or ``watchdog``).

    Linux: the kernel sends SIGKILL when the parent dies (``PR_SET_PDEATHSIG``; strictly,
    when the parent *thread* that started the worker ends). Elsewhere, or when prctl fails,
    a daemon thread polls ``os.getppid()`` every 0.5 s.
    """
    how = ""
    if use_prctl and sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL(None, use_errno=True)
            if libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0:
                how = "prctl"
    if os.getppid() != parent_pid:  # the parent died before the guard was in place
        os._exit(1)
    if not how:
        threading.Thread(target=_watch_parent, args=(parent_pid,), daemon=True,
                         name="evomotion-parent-watchdog").start()
        how = "watchdog"
    return how


def _worker_main(conn: Any, make_problem: Callable[[Any], Problem], problem_cfg: Any,
                 parent_pid: int, use_prctl: bool) -> None:
    """A process worker: build the problem once, then evaluate ``(task, genomes)`` messages."""
    guard = _die_with_parent(parent_pid, use_prctl)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    os.environ.update(WORKER_ENV)
    try:
        problem = make_problem(problem_cfg)
        spec = (problem.sense, tuple(problem.metric_names))
    except Exception as e:  # noqa: BLE001 - reported to the parent as one line
        conn.send(("error", f"{type(e).__name__}: {e}"))
        return
    conn.send(("ready", guard, *spec))
    while True:
        try:
            msg = conn.recv()
        except (EOFError, OSError):
            return
        if msg is None:
            return
        task, genomes = msg
        conn.send((task, evaluate_safely(problem, genomes)))


@contextlib.contextmanager
def _environ(env: dict[str, str]) -> Iterator[None]:
    """``env`` set while a worker is spawned, so BLAS reads it when the worker imports it."""
    old = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


class _Worker:
    """One worker process, its end of the pipe, and what it is doing."""

    def __init__(self, process: Any, conn: Any) -> None:
        self.process, self.conn = process, conn
        self.pid: int = process.pid
        self.state = "starting"  # -> "idle" <-> "busy"
        self.task: int | None = None
        self.guard = ""
        self.t0 = time.monotonic()

    def death_reason(self) -> str:
        self.process.join(timeout=2.0)
        if self.process.is_alive():  # closed its pipe but lives on: finish it
            self.process.kill()
            self.process.join(timeout=2.0)
        code = self.process.exitcode
        if code is not None and code < 0:
            try:
                return f"signal {signal.Signals(-code).name}"
            except ValueError:
                return f"signal {-code}"
        return f"exit code {code}"

    def close(self) -> None:
        self.conn.close()
        with contextlib.suppress(ValueError):  # still running after kill + join
            self.process.close()


Piece = tuple[int, int, int]  # rows start, stop, attempts left


class ProcessEvaluator:
    """Spawned worker processes on this machine; each builds the problem once.

    One chunk per worker at a time, so a worker that dies (segfault, ``os._exit``, SIGKILL,
    OOM kill) names the chunk it was running: the worker is replaced and the chunk re-run.
    A chunk that kills ``max_attempts`` workers is split in halves, and a half that kills
    a worker again is split again, down to the individual; an individual that kills a worker
    on its own gets the worst fitness (``failed``, a message in ``errors``) and everything
    else its normal result. Counters: ``replaced`` (workers replaced), ``failed_rows``
    (individuals marked worst). Workers end with this process, even on ``kill -9``
    (``PR_SET_PDEATHSIG`` on Linux, else a watchdog thread; ``die_with_parent = False``:
    the watchdog only; the kernel's signal follows the *thread* that started a worker, so
    use the evaluator from one long-lived thread, as the run loop does). Workers ignore
    SIGINT; a Ctrl-C is handled here. A problem that cannot be built, or workers that keep
    dying while building it, raise :class:`ClusterError`.
    """

    name = "process"
    max_attempts = 2
    start_timeout_s = 120.0
    poll_s = 1.0
    die_with_parent = True  # prctl(PR_SET_PDEATHSIG) where it exists; False: watchdog only

    def __init__(self, make_problem: Callable[[Any], Problem], problem_cfg: Any,
                 workers: int = 0, chunks_per_worker: int = 4, address: str = "",
                 max_attempts: int | None = None) -> None:
        self.workers = workers or os.cpu_count() or 1
        self.chunks_per_worker = chunks_per_worker
        self.max_attempts = max_attempts or self.max_attempts
        self.replaced = 0
        self.failed_rows = 0
        self.sense: Sense = "min"
        self.metric_names: tuple[str, ...] = ()
        # spawn, not fork: MuJoCo and BLAS thread pools do not survive a fork safely
        self._ctx = multiprocessing.get_context("spawn")
        self._args = (make_problem, worker_config(problem_cfg))
        self._tasks = itertools.count()
        self._start_failures = 0  # replacement workers in a row that died while starting
        self._slots: list[_Worker] = []
        try:
            self._slots = [self._start() for _ in range(self.workers)]
            while any(w.state == "starting" for w in self._slots):
                self._poll({}, deque(), {})
        except BaseException:
            self.close()
            raise

    def worker_pids(self) -> list[int]:
        """Process ids of the current workers (for diagnostics and tests)."""
        return [w.pid for w in self._slots]

    def worker_guards(self) -> list[str]:
        """How each ready worker follows its parent's death: ``prctl`` or ``watchdog``."""
        return [w.guard for w in self._slots]

    def __call__(self, genomes: np.ndarray) -> Evaluation:
        chunks = split_chunks(len(genomes), self.workers * self.chunks_per_worker)
        todo: deque[Piece] = deque((s.start, s.stop, self.max_attempts) for s in chunks)
        running: dict[int, Piece] = {}  # task id -> piece
        done: dict[int, Evaluation] = {}  # rows start -> result
        while todo or running:
            for w in self._slots:
                if todo and w.state == "idle":
                    self._send(w, todo.popleft(), genomes, running)
            self._poll(running, todo, done)
        return Evaluation.concat([done[k] for k in sorted(done)])

    def _start(self) -> _Worker:
        conn, child = self._ctx.Pipe(duplex=True)
        process = self._ctx.Process(
            target=_worker_main, name="evomotion-worker", daemon=True,
            args=(child, *self._args, os.getpid(), self.die_with_parent))
        with _environ(WORKER_ENV):
            process.start()
        child.close()  # so that the worker's death reads as EOF here
        return _Worker(process, conn)

    def _send(self, w: _Worker, piece: Piece, genomes: np.ndarray,
              running: dict[int, Piece]) -> None:
        task = next(self._tasks)
        running[task] = piece
        w.state, w.task = "busy", task
        with contextlib.suppress(OSError):  # it died: its sentinel says so in _poll
            w.conn.send((task, genomes[piece[0]:piece[1]]))

    def _poll(self, running: dict[int, Piece], todo: deque[Piece],
              done: dict[int, Evaluation]) -> None:
        """Wait for messages or deaths of workers and handle them."""
        by_handle = {}
        for w in self._slots:
            by_handle[w.conn] = by_handle[w.process.sentinel] = w
        ready = wait_ready(list(by_handle), timeout=self.poll_s)
        if not ready:
            self._check_starts()
        for w in dict.fromkeys(by_handle[r] for r in ready):
            msg, alive = None, True
            try:
                if w.conn.poll():
                    msg = w.conn.recv()
                else:
                    alive = w.process.is_alive()
            except Exception:  # noqa: BLE001 - EOF, broken pipe or a torn message: it died
                alive = False
            if not alive:
                self._lost(w, running, todo, done)
            elif msg is not None:
                self._message(w, msg, running, done)

    def _message(self, w: _Worker, msg: tuple, running: dict[int, Piece],
                 done: dict[int, Evaluation]) -> None:
        if msg[0] == "error":
            raise ClusterError(f"a process worker could not build the problem: {msg[1]}")
        if msg[0] == "ready":
            w.guard, self.sense, self.metric_names = msg[1], msg[2], msg[3]
            self._start_failures = 0
        elif msg[0] in running:  # else a result of a batch that was interrupted: dropped
            done[running.pop(msg[0])[0]] = msg[1]
        w.state, w.task = "idle", None

    def _lost(self, w: _Worker, running: dict[int, Piece], todo: deque[Piece],
              done: dict[int, Evaluation]) -> None:
        """``w`` died: replace it and retry, split or give up the piece it was running."""
        slot, reason = self._slots.index(w), w.death_reason()
        w.close()
        if w.state == "starting":
            self._start_failures += 1
            if self._start_failures >= self.max_attempts * self.workers:
                del self._slots[slot]
                raise ClusterError(f"{self._start_failures} process workers in a row died "
                                   f"while building the problem ({reason})")
        self._slots[slot] = self._start()
        self.replaced += 1
        piece = running.pop(w.task, None) if w.task is not None else None
        if piece is None:
            log.warning("process worker %d died (%s) while %s; replaced", w.pid, reason,
                        "starting" if w.state == "starting" else "idle")
            return
        start, stop, left = piece
        rows = f"row {start}" if stop - start == 1 else f"rows {start}-{stop - 1}"
        if left > 1:
            log.warning("process worker died (%s) evaluating %s; replaced, chunk re-run",
                        reason, rows)
            todo.appendleft((start, stop, left - 1))
        elif stop - start > 1:
            log.warning("process worker died (%s) evaluating %s; replaced, chunk split in "
                        "halves", reason, rows)
            mid = (start + stop) // 2
            todo.extendleft([(mid, stop, 1), (start, mid, 1)])  # the first half first
        else:
            self.failed_rows += 1
            ev = failed_evaluation(1, self.sense, self.metric_names)
            ev.errors.append(f"worker died ({reason}) evaluating row {start}; it gets the "
                             f"worst fitness")
            log.warning(ev.errors[-1])
            done[start] = ev

    def _check_starts(self) -> None:
        """Raise when every worker has been starting for longer than ``start_timeout_s``."""
        if self._slots and all(w.state == "starting" for w in self._slots):
            waited = time.monotonic() - min(w.t0 for w in self._slots)
            if waited > self.start_timeout_s:
                raise ClusterError(f"no process worker built the problem within "
                                   f"{self.start_timeout_s:g} s")

    def close(self) -> None:
        """Stop the workers: idle ones finish, busy or starting ones are killed."""
        slots, self._slots = self._slots, []
        for w in slots:
            if w.state == "idle":
                with contextlib.suppress(OSError):
                    w.conn.send(None)
            else:
                w.process.kill()
        deadline = time.monotonic() + 5.0
        for w in slots:
            w.process.join(timeout=max(0.0, deadline - time.monotonic()))
            if w.process.is_alive():
                w.process.kill()
                w.process.join(timeout=2.0)
            w.close()


EVALUATORS: dict[str, str | type] = {
    "serial": SerialEvaluator,
    "process": ProcessEvaluator,
    "ray": "evomotion.run.ray_evaluator:RayEvaluator",
    "dask": "evomotion.run.dask_evaluator:DaskEvaluator",
}


def make_evaluator(name: str, make_problem: Callable[[Any], Problem], problem_cfg: Any,
                   workers: int = 0, chunks_per_worker: int = 4, address: str = ""):
    """Build the evaluator registered as ``name`` (an import path string is loaded lazily)."""
    entry = lookup(EVALUATORS, "evaluator", name)
    if isinstance(entry, str):
        module, attr = entry.split(":")
        entry = getattr(importlib.import_module(module), attr)
    return entry(make_problem, problem_cfg, workers=workers,
                 chunks_per_worker=chunks_per_worker, address=address)
