"""The ``ray`` evaluator: long-lived Ray actors evaluate chunks of each generation.

Each actor builds the problem once (the MuJoCo model stays loaded) and then evaluates
contiguous chunks of the batch, a few per actor per generation (``chunks_per_worker``),
never one task per individual. A chunk goes to whichever actor is free, one chunk per actor
at a time, so a dead actor always names the one chunk it was running. Results are assembled
in submission order, so the :class:`~evomotion.core.problem.Evaluation` is bit-identical to
``serial`` (problems are deterministic functions of each genome).

Faults: an actor that dies (crash, OOM kill, lost node) is replaced and its chunk re-run; a
chunk that kills ``max_attempts`` actors gets the worst fitness (``failed`` and a
message in ``errors``, which the runner logs) and the run goes on. When no actor can be
started any more (every node gone, or the driver lost its connection) a
:class:`ClusterError` is raised: the runner then checkpoints the last completed
generation and ``evomotion resume DIR --evaluator serial`` continues on one machine.

Ray is an optional extra (``pip install 'evomotion[ray]'``); it is imported when the
evaluator is built. See ``docs/cluster.md`` for a multi-machine recipe.
"""

from __future__ import annotations

import contextlib
import logging
import os
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import numpy as np

from evomotion.core.problem import Evaluation, Problem, failed_evaluation
from evomotion.errors import ClusterError, InputError
from evomotion.run.evaluators import (
    WORKER_ENV,
    evaluate_safely,
    split_chunks,
    worker_config,
)

log = logging.getLogger("evomotion.run.ray")

class ProblemActor:
    """The body of one Ray actor: builds the problem once, then evaluates chunks."""

    def __init__(self, make_problem: Callable[[Any], Problem], problem_cfg: Any) -> None:
        for key, val in WORKER_ENV.items():
            os.environ.setdefault(key, val)
        self.problem = make_problem(problem_cfg)

    def ready(self) -> int:
        """The worker's process id (also proves the problem was built)."""
        return os.getpid()

    def spec(self) -> tuple[str, tuple[str, ...]]:
        return self.problem.sense, tuple(self.problem.metric_names)

    def environ(self, key: str) -> str | None:
        return os.environ.get(key)

    def evaluate(self, genomes: np.ndarray) -> Evaluation:
        return evaluate_safely(self.problem, genomes)


class RayEvaluator:
    """Evaluate on a Ray cluster at ``address`` (``HOST:PORT``, or ``auto``: the one this
    machine belongs to); a new local cluster when ``address`` is empty.

    ``workers = 0`` starts one actor per CPU of the cluster. ``max_attempts``: how many actors
    a chunk may lose before its individuals are marked worst. ``start_timeout_s``: how long
    to wait for a worker when no other worker can make progress before giving up.
    """

    name = "ray"
    max_attempts = 3
    start_timeout_s = 120.0
    poll_s = 1.0

    def __init__(self, make_problem: Callable[[Any], Problem], problem_cfg: Any,
                 workers: int = 0, chunks_per_worker: int = 4, address: str = "",
                 max_attempts: int | None = None, start_timeout_s: float | None = None) -> None:
        try:
            import ray
        except ImportError:
            raise InputError("the ray evaluator needs Ray: pip install 'evomotion[ray]'") from None

        self._ray = ray
        self.address = address
        self.chunks_per_worker = chunks_per_worker
        self.max_attempts = max_attempts or self.max_attempts
        self.start_timeout_s = start_timeout_s or self.start_timeout_s
        self.replaced = 0  # actors that died and were replaced
        self.failed_chunks = 0  # chunks given up after max_attempts
        self._make_problem, self._problem_cfg = make_problem, worker_config(problem_cfg)
        self._own_ray = not ray.is_initialized()
        if self._own_ray:
            try:
                # "local": always a fresh local cluster, never one found in /tmp/ray
                # a local cluster started here listens on 127.0.0.1 only (docs/cluster.md
                # says how to open one up with token authentication)
                local: dict[str, Any] = {} if address else {"_node_ip_address": "127.0.0.1"}
                ray.init(address=address or "local",
                         num_cpus=None if address else (workers or None),
                         include_dashboard=False, logging_level=logging.WARNING,
                         log_to_driver=False, runtime_env={"env_vars": WORKER_ENV}, **local)
            except ConnectionError as e:
                raise ClusterError(f"cannot reach the Ray cluster at {address}: {e}") from e
        cpus = int(ray.cluster_resources().get("CPU", 0))
        n = workers or cpus
        if n < 1 or n > cpus:
            self.close()
            raise ClusterError(f"the Ray cluster {self._where()} has {cpus} CPUs; cannot start "
                               f"{n} one-CPU evaluation workers")
        self._actor_cls = ray.remote(num_cpus=1, max_restarts=0)(ProblemActor)
        self.actors = [self._new_actor() for _ in range(n)]
        self._starting: dict[Any, tuple[int, float]] = {}
        self._start_failures = 0  # consecutive replacement workers that failed to start
        ready = [a.ready.remote() for a in self.actors]
        done, _ = ray.wait(ready, num_returns=n, timeout=self.start_timeout_s)
        if len(done) < n:
            self.close()
            raise ClusterError(f"only {len(done)} of {n} Ray workers started within "
                               f"{self.start_timeout_s:g} s; does the cluster have {n} free CPUs?")
        try:
            ray.get(ready)
            self.sense, self.metric_names = ray.get(self.actors[0].spec.remote())
        except ray.exceptions.RayActorError as e:
            self.close()
            raise ClusterError(f"Ray workers could not build the problem: {e}") from e

    def worker_pids(self) -> list[int]:
        """Process ids of the current actors (for diagnostics and tests)."""
        return self._ray.get([a.ready.remote() for a in self.actors])

    def _new_actor(self):
        return self._actor_cls.options(runtime_env={"env_vars": WORKER_ENV}).remote(
            self._make_problem, self._problem_cfg)

    def _replace(self, slot: int) -> None:
        ray = self._ray
        with contextlib.suppress(Exception):  # it is already dead or unreachable
            ray.kill(self.actors[slot], no_restart=True)
        self.replaced += 1
        self.actors[slot] = self._new_actor()
        self._starting[self.actors[slot].ready.remote()] = (slot, time.monotonic())

    def __call__(self, genomes: np.ndarray) -> Evaluation:
        ray = self._ray
        genomes = np.ascontiguousarray(genomes, dtype=float)
        chunks = split_chunks(len(genomes), len(self.actors) * self.chunks_per_worker)
        parts: list[Evaluation | None] = [None] * len(chunks)
        tries = [0] * len(chunks)
        todo = deque(range(len(chunks)))
        busy = {slot for slot, _ in self._starting.values()}
        idle = deque(s for s in range(len(self.actors)) if s not in busy)
        running: dict[Any, tuple[int, int]] = {}  # result ref -> (chunk, actor slot)
        try:
            while todo or running:
                while todo and idle:
                    k, slot = todo.popleft(), idle.popleft()
                    ref = self.actors[slot].evaluate.remote(genomes[chunks[k]])
                    running[ref] = (k, slot)
                done, _ = ray.wait(list(running) + list(self._starting), num_returns=1,
                                   timeout=self.poll_s)
                if not done:
                    self._check_progress(running, idle)
                for ref in done:
                    if ref in self._starting:
                        self._started(ref, idle)
                        continue
                    k, slot = running.pop(ref)
                    try:
                        parts[k] = ray.get(ref)
                        idle.append(slot)
                    except (ray.exceptions.RayActorError, ray.exceptions.WorkerCrashedError,
                            ray.exceptions.ObjectLostError) as e:
                        tries[k] += 1
                        self._replace(slot)
                        self._chunk_lost(k, chunks[k], tries[k], e, parts, todo)
        except ray.exceptions.RayError as e:
            raise ClusterError(f"Ray evaluation failed {self._where()}: {e}") from e
        return Evaluation.concat(parts)  # type: ignore[arg-type]

    def _chunk_lost(self, k: int, rows: slice, tries: int, error: Exception,
                    parts: list, todo: deque) -> None:
        what = f"rows {rows.start}-{rows.stop - 1}"
        reason = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        if tries < self.max_attempts:
            log.warning("ray worker died evaluating %s (%s); replaced, chunk re-run", what, reason)
            todo.appendleft(k)
            return
        self.failed_chunks += 1
        ev = failed_evaluation(rows.stop - rows.start, self.sense, self.metric_names)
        ev.errors.append(f"ray chunk {what} killed {tries} workers ({type(error).__name__}: "
                         f"{reason}); marked worst")
        log.warning(ev.errors[-1])
        parts[k] = ev

    def _started(self, ref, idle: deque) -> None:
        slot, _ = self._starting.pop(ref)
        try:
            self._ray.get(ref)
        except self._ray.exceptions.RayActorError as e:
            self._start_failures += 1
            if self._start_failures >= self.max_attempts * len(self.actors):
                raise ClusterError(f"{self._start_failures} replacement Ray workers in a "
                                       f"row failed to start {self._where()}: {e}") from e
            self._replace(slot)
            return
        self._start_failures = 0
        idle.append(slot)

    def _check_progress(self, running: dict, idle: deque) -> None:
        """Raise when nothing runs and every pending worker start has timed out."""
        if running or idle or not self._starting:
            return
        oldest = min(t0 for _, t0 in self._starting.values())
        if time.monotonic() - oldest > self.start_timeout_s:
            raise ClusterError(
                f"lost the Ray cluster {self._where()}: all {len(self.actors)} workers died and "
                f"none could be restarted within {self.start_timeout_s:g} s")

    def _where(self) -> str:
        return f"at {self.address}" if self.address else "(local)"

    def close(self) -> None:
        ray = self._ray
        for a in getattr(self, "actors", []):
            with contextlib.suppress(Exception):  # best effort on a possibly lost cluster
                ray.kill(a, no_restart=True)
        self.actors = []
        self._starting = {}
        if self._own_ray and ray.is_initialized():
            ray.shutdown()
