"""The ``dask`` evaluator: chunks of each generation as tasks on a Dask distributed cluster.

``address`` is a scheduler (``tcp://HOST:8786``); without one a local cluster of one
single-threaded worker process per core is started. Each worker thread builds the problem
once, on its first chunk, and keeps it for the rest of the run (a per-thread cache keyed by
this evaluator's token, so threaded workers never share a MuJoCo model). The batch is split
into a few chunks per worker thread (``chunks_per_worker``), never one task per individual,
and results are assembled in submission order: bit-identical to ``serial``.

Faults are the scheduler's: a worker process that dies is restarted by its nanny and the
chunk it held is re-run elsewhere; a chunk that kills ``distributed.scheduler.allowed-failures``
workers (default 3) fails with ``KilledWorker``; it is then re-run alone (a worker may hold
an innocent chunk queued behind the culprit, which the scheduler blames too), and if it
kills its workers again its individuals get the worst fitness with a message in
``Evaluation.errors`` while the run goes on. When the scheduler goes away,
or has had no worker for ``start_timeout_s``, a :class:`ClusterError` is raised and the runner
checkpoints the last completed generation (``evomotion resume DIR --evaluator serial``).

Dask is an optional extra (``pip install 'evomotion[dask]'``). Workers get
``OMP_NUM_THREADS=1`` from Dask's nanny (``distributed.nanny.pre-spawn-environ``) and again
here before the problem is built.
"""

from __future__ import annotations

import logging
import os
import threading
import time
import uuid
from collections.abc import Callable
from typing import Any

import numpy as np

from evomotion.core.problem import Evaluation, Problem, Sense, failed_evaluation
from evomotion.errors import ClusterError, InputError
from evomotion.run.evaluators import WORKER_ENV, evaluate_safely, split_chunks, worker_config

log = logging.getLogger("evomotion.run.dask")

_LOCAL = threading.local()  # per worker thread: {token: problem}


def evaluate_chunk(token: str, make_problem: Callable[[Any], Problem], problem_cfg: Any,
                   genomes: np.ndarray) -> Evaluation:
    """The Dask task: evaluate one chunk with this thread's problem (built on first use)."""
    cache = getattr(_LOCAL, "problems", None)
    if cache is None or token not in cache:
        for key, val in WORKER_ENV.items():
            os.environ.setdefault(key, val)
        _LOCAL.problems = cache = {token: make_problem(problem_cfg)}  # one run at a time
    return evaluate_safely(cache[token], genomes)


def worker_environ(key: str) -> str | None:
    """A worker's environment variable (diagnostics and tests)."""
    return os.environ.get(key)


class DaskEvaluator:
    """Evaluate on a Dask cluster at ``address`` (``tcp://HOST:8786``), local when empty."""

    name = "dask"
    start_timeout_s = 120.0
    poll_s = 1.0

    def __init__(self, make_problem: Callable[[Any], Problem], problem_cfg: Any,
                 workers: int = 0, chunks_per_worker: int = 4, address: str = "",
                 start_timeout_s: float | None = None) -> None:
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise InputError("the dask evaluator needs Dask: pip install "
                             "'evomotion[dask]'") from None
        self.address = address
        self.chunks_per_worker = chunks_per_worker
        self.start_timeout_s = start_timeout_s or self.start_timeout_s
        self._make_problem, self._problem_cfg = make_problem, worker_config(problem_cfg)
        self._token = uuid.uuid4().hex
        self._generation = 0
        self.cluster = None
        try:
            if address:
                self.client = Client(address, timeout=self.start_timeout_s)
            else:
                self.cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1,
                                            threads_per_worker=1, processes=True,
                                            host="127.0.0.1",  # scheduler and workers
                                            # a free localhost port (None still binds 8787)
                                            dashboard_address="127.0.0.1:0",
                                            silence_logs=logging.WARNING)
                self.client = Client(self.cluster)
            self.client.wait_for_workers(1, timeout=self.start_timeout_s)
        except (OSError, TimeoutError) as e:
            self.close()
            raise ClusterError(f"cannot reach the Dask scheduler {self._where()}: {e}") from e
        self.threads = workers or sum(self.client.nthreads().values())

    def __call__(self, genomes: np.ndarray) -> Evaluation:
        genomes = np.ascontiguousarray(genomes, dtype=float)
        chunks = split_chunks(len(genomes), self.threads * self.chunks_per_worker)
        self._generation += 1
        tag = f"evomotion-{self._token[:8]}-{self._generation}"
        parts = self._run([genomes[s] for s in chunks], [f"{tag}-{k}" for k in
                                                         range(len(chunks))])
        for k, s in enumerate(chunks):
            if parts[k] is None:
                # A worker died with this chunk on it, allowed-failures times; the chunks
                # queued behind the culprit on that worker are blamed too, so each one is
                # re-run alone: only a chunk that kills its worker by itself is marked.
                parts[k] = self._run([genomes[s]], [f"{tag}-{k}-alone"])[0]
            if parts[k] is None:
                ev = failed_evaluation(s.stop - s.start, *self._spec())
                ev.errors.append(f"dask chunk rows {s.start}-{s.stop - 1} killed its workers "
                                 f"(KilledWorker); marked worst")
                log.warning(ev.errors[-1])
                parts[k] = ev
        return Evaluation.concat([p for p in parts if p is not None])  # none is left None

    def _run(self, batches: list[np.ndarray], keys: list[str]) -> list[Evaluation | None]:
        """Evaluate ``batches`` as tasks, in order; ``None`` where the task hit KilledWorker."""
        from distributed import KilledWorker, wait

        m = len(batches)
        try:  # one message to the scheduler for all the chunks
            futures = self.client.map(evaluate_chunk, [self._token] * m,
                                      [self._make_problem] * m, [self._problem_cfg] * m,
                                      batches, pure=False, key=keys)
            no_worker_since = None
            while True:
                try:
                    wait(futures, timeout=self.poll_s)
                    break
                except TimeoutError:
                    no_worker_since = self._check_cluster(no_worker_since)
        except ClusterError:
            raise
        except Exception as e:  # noqa: BLE001 - comm errors of a lost scheduler
            raise ClusterError(f"lost the Dask scheduler {self._where()}: "
                               f"{type(e).__name__}: {e}") from e
        out: list[Evaluation | None] = []
        for fut in futures:
            try:
                out.append(fut.result())
            except KilledWorker:
                out.append(None)
            except Exception as e:  # noqa: BLE001 - problem errors are caught in the task
                raise ClusterError(f"Dask evaluation failed {self._where()}: "
                                   f"{type(e).__name__}: {e}") from e
        return out

    def _check_cluster(self, no_worker_since: float | None) -> float | None:
        """Raise when the scheduler is gone or has had no worker for ``start_timeout_s``."""
        if self.client.status != "running":
            raise ClusterError(f"lost the Dask scheduler {self._where()} "
                               f"(client {self.client.status})")
        if self.client.nthreads():
            return None
        now = time.monotonic()
        if no_worker_since is None:
            return now
        if now - no_worker_since > self.start_timeout_s:
            raise ClusterError(f"the Dask cluster {self._where()} has had no worker for "
                               f"{self.start_timeout_s:g} s")
        return no_worker_since

    def _spec(self) -> tuple[Sense, tuple[str, ...]]:
        problem = self._make_problem(self._problem_cfg)
        return problem.sense, tuple(problem.metric_names)

    def _where(self) -> str:
        return f"at {self.address}" if self.address else "(local)"

    def close(self) -> None:
        for obj in (getattr(self, "client", None), self.cluster):
            if obj is not None:
                try:
                    obj.close()
                except Exception as e:  # noqa: BLE001 - best effort on a possibly lost cluster
                    log.debug("closing %s: %s", type(obj).__name__, e)
        self.cluster = None
