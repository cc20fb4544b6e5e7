"""Evaluators: the seam between an optimizer's batch and the machines that evaluate it.

All evaluators return the same :class:`~evomotion.core.problem.Evaluation` for the same
genomes, in submission order, because problems are deterministic functions of each genome.
``serial`` evaluates the batch in-process; ``process`` splits it into chunks (a few per
worker, never one task per individual) sent to a stdlib process pool whose workers build the
problem once in their initializer. ``ray`` and ``dask`` are optional extras registered here
lazily.
"""

from __future__ import annotations

import importlib
import multiprocessing
import os
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import numpy as np

from evomotion.core.problem import Evaluation, Problem, failed_evaluation, sanitize
from evomotion.core.registry import lookup

WORKER_ENV = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}


def worker_config(problem_cfg: Any) -> Any:
    """The problem config a one-core worker builds from (process, Ray and Dask workers).

    The workers already fill every core, one per core, so a problem that would otherwise use
    several threads (e.g. ``mujoco.rollout`` threads left at 0 = all cores) says how to run on
    one: a problem config with a ``for_worker()`` method returns the config a one-core worker
    should build; any other config is used unchanged.
    """
    hook = getattr(problem_cfg, "for_worker", None)
    return hook() if callable(hook) else problem_cfg


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


_WORKER_PROBLEM: Problem | None = None


def _init_worker(make_problem: Callable[[Any], Problem], problem_cfg: Any) -> None:
    global _WORKER_PROBLEM
    os.environ.update(WORKER_ENV)
    _WORKER_PROBLEM = make_problem(problem_cfg)


def _eval_chunk(genomes: np.ndarray) -> Evaluation:
    assert _WORKER_PROBLEM is not None
    return evaluate_safely(_WORKER_PROBLEM, genomes)


class ProcessEvaluator:
    """A stdlib process pool; each worker builds the problem once."""

    name = "process"

    def __init__(self, make_problem: Callable[[Any], Problem], problem_cfg: Any,
                 workers: int = 0, chunks_per_worker: int = 4, address: str = "") -> None:
        self.workers = workers or os.cpu_count() or 1
        self.chunks_per_worker = chunks_per_worker
        # spawn, not fork: MuJoCo and BLAS thread pools do not survive a fork safely
        ctx = multiprocessing.get_context("spawn")
        self._pool = ProcessPoolExecutor(self.workers, mp_context=ctx, initializer=_init_worker,
                                         initargs=(make_problem, worker_config(problem_cfg)))

    def __call__(self, genomes: np.ndarray) -> Evaluation:
        chunks = split_chunks(len(genomes), self.workers * self.chunks_per_worker)
        parts = list(self._pool.map(_eval_chunk, [genomes[s] for s in chunks]))
        return Evaluation.concat(parts)

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)


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
