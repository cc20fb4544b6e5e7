"""The dask evaluator on a local Dask cluster of two single-threaded worker processes."""

from __future__ import annotations

import os
import signal
import sys
import threading

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("distributed")
import dask  # noqa: E402
from distributed import Client, LocalCluster  # noqa: E402

from evomotion.errors import ClusterError  # noqa: E402
from evomotion.run.config import resolve_config  # noqa: E402
from evomotion.run.dask_evaluator import DaskEvaluator, worker_environ  # noqa: E402
from evomotion.run.evaluators import make_evaluator  # noqa: E402
from evomotion.run.runner import run_study  # noqa: E402
from evomotion.studies import STUDIES, get_study  # noqa: E402

sys.path.insert(0, os.path.dirname(__file__))
from cluster_helpers import (  # noqa: E402
    CrashConfig,
    CrashProblem,
    assert_same_evaluation,
    assert_same_run,
    serial_evaluation,
)
from toy_study import STUDY as TOY  # noqa: E402


def _local_cluster(n: int = 2) -> LocalCluster:
    return LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                        dashboard_address="127.0.0.1:0", silence_logs=50)


@pytest.fixture(scope="module")
def address():
    with dask.config.set({"distributed.scheduler.allowed-failures": 1}):
        cluster = _local_cluster()
    yield cluster.scheduler_address
    cluster.close()


def _study_or_skip(name: str):
    if name not in STUDIES:
        pytest.skip(f"study {name!r} is not registered yet")
    return get_study(name)


def test_any_batch_and_chunking_matches_serial(address):
    """Order, NaN flags and isolated exceptions survive any split into chunks."""
    ev = DaskEvaluator(TOY.make_problem, TOY.problem_config(), address=address)

    @settings(max_examples=12, deadline=None)
    @given(n=st.integers(1, 40), chunks_per_worker=st.integers(1, 7),
           seed=st.integers(0, 2**16))
    def check(n, chunks_per_worker, seed):
        genomes = np.random.default_rng(seed).uniform(-5, 5, (n, TOY.problem_config().dim))
        ev.chunks_per_worker = chunks_per_worker
        expected = serial_evaluation(TOY, TOY.problem_config(), genomes)
        assert_same_evaluation(ev(genomes), expected)

    try:
        check()
    finally:
        ev.close()


def test_toy_run_identical_to_serial(address, tmp_path):
    cfg_s = resolve_config(TOY, None, ["run.generations=5"])
    cfg_d = resolve_config(TOY, None, ["run.generations=5", "run.evaluator=dask",
                                       f"run.address={address!r}", "run.chunks_per_worker=3"])
    run_study(TOY, cfg_s, tmp_path / "serial", quiet=True)
    run_study(TOY, cfg_d, tmp_path / "dask", quiet=True)
    assert_same_run(tmp_path / "serial", tmp_path / "dask")


def test_local_cluster_when_no_address(tmp_path):
    study = get_study("functions")
    cfg = resolve_config(study, None, ["problem.name=ackley", "problem.dim=9"]).problem
    genomes = study.make_problem(cfg).genome.sample(np.random.default_rng(5), 77)
    ev = make_evaluator("dask", study.make_problem, cfg, workers=2, chunks_per_worker=4)
    try:
        assert ev.cluster is not None and ev.threads == 2
        assert sorted(ev.client.run(worker_environ, "OMP_NUM_THREADS").values()) == ["1", "1"]
        assert_same_evaluation(ev(genomes), serial_evaluation(study, cfg, genomes))
    finally:
        ev.close()


def test_humanoid_step_generation_identical_to_serial(address):
    study = _study_or_skip("humanoid-step")
    cfg = resolve_config(study, None, []).problem
    genomes = study.make_problem(cfg).genome.sample(np.random.default_rng(1), 8)
    ev = DaskEvaluator(study.make_problem, cfg, chunks_per_worker=2, address=address)
    try:
        assert_same_evaluation(ev(genomes), serial_evaluation(study, cfg, genomes))
    finally:
        ev.close()


def test_grid_path_run_identical_to_serial(address, tmp_path):
    """The grid-path problem through the generic ask/tell loop (its default cGA): the study's
    own driver evaluates in-process and does not take an evaluator."""
    study = _study_or_skip("grid-path")
    for name in ("serial", "dask"):
        cfg = resolve_config(study, None, ["run.generations=6", f"run.evaluator={name!r}",
                                           f"run.address={address!r}"])
        run_study(study, cfg, tmp_path / name, quiet=True)
    assert_same_run(tmp_path / "serial", tmp_path / "dask")


def test_worker_killed_mid_generation_run_completes_identically(address, tmp_path,
                                                                monkeypatch):
    overrides = ["run.generations=4", "problem.sleep_s=0.1", "problem.raise_above=9"]
    run_study(TOY, resolve_config(TOY, None, overrides), tmp_path / "serial", quiet=True)
    calls = {"n": 0}
    original = DaskEvaluator.__call__

    def call(self, genomes):
        calls["n"] += 1
        if calls["n"] == 3:  # SIGKILL one worker while generation 2's chunks run
            calls["pid"] = pid = next(iter(self.client.run(os.getpid).values()))
            threading.Timer(0.1, os.kill, (pid, signal.SIGKILL)).start()
        return original(self, genomes)

    monkeypatch.setattr(DaskEvaluator, "__call__", call)
    cfg = resolve_config(TOY, None, [*overrides, "run.evaluator='dask'",
                                     f"run.address={address!r}", "run.chunks_per_worker=3"])
    res = run_study(TOY, cfg, tmp_path / "dask", quiet=True)
    assert res.stop_reason == "generations" and calls["n"] == 5
    with Client(address) as client:  # the nanny replaced the killed worker process
        pids = set(client.run(os.getpid).values())
    assert len(pids) == 2 and calls["pid"] not in pids
    assert_same_run(tmp_path / "serial", tmp_path / "dask")


def test_chunk_that_keeps_killing_workers_is_marked_worst(address):
    cfg = CrashConfig()
    genomes = np.random.default_rng(2).uniform(-0.9, 0.9, (12, cfg.dim))
    genomes[7, 0] = 0.99  # rows 6-8 form the poisoned chunk (4 chunks of 3)
    ev = DaskEvaluator(CrashProblem, cfg, chunks_per_worker=2, address=address)
    try:
        out = ev(genomes)
        bad = np.zeros(12, bool)
        bad[6:9] = True
        np.testing.assert_array_equal(out.failed, bad)
        assert np.all(out.fitness[bad] == np.inf)
        assert out.fitness[~bad].tobytes() == (genomes[~bad] ** 2).sum(1).tobytes()
        assert len(out.errors) == 1 and "rows 6-8" in out.errors[0]
    finally:
        ev.close()


def test_losing_the_cluster_checkpoints_and_serial_resume_is_identical(tmp_path, monkeypatch):
    cluster = _local_cluster()
    sets = ["problem.dim=6", "run.generations=8", "algorithm.pop_size=40"]
    study = get_study("functions")
    run_study(study, resolve_config(study, None, sets), tmp_path / "serial", quiet=True)
    calls = {"n": 0}
    original = DaskEvaluator.__call__

    def call(self, genomes):
        calls["n"] += 1
        if calls["n"] == 4:
            self.poll_s = 0.2
            cluster.close()
        return original(self, genomes)

    monkeypatch.setattr(DaskEvaluator, "__call__", call)
    out = tmp_path / "lost"
    cfg = resolve_config(study, None, [*sets, "run.evaluator='dask'",
                                       f"run.address={cluster.scheduler_address!r}"])
    with pytest.raises(ClusterError, match="Dask"):
        run_study(study, cfg, out, quiet=True)
    log = (out / "log.txt").read_text()
    assert "run failed at generation 2" in log and "resume" in log
    run_study(study, resolve_config(study, None, sets), out, quiet=True, resume=True)
    assert_same_run(tmp_path / "serial", out)


def test_unreachable_scheduler_is_a_clear_error():
    with pytest.raises(ClusterError, match="cannot reach the Dask scheduler"):
        DaskEvaluator(TOY.make_problem, TOY.problem_config(), address="tcp://127.0.0.1:9",
                      start_timeout_s=1.0)


def test_missing_dask_is_a_one_line_input_error(monkeypatch):
    from evomotion.errors import InputError

    monkeypatch.setitem(sys.modules, "distributed", None)  # "import distributed" now fails
    with pytest.raises(InputError, match=r"pip install 'evomotion\[dask\]'"):
        make_evaluator("dask", TOY.make_problem, TOY.problem_config())
