"""The ray and dask evaluators, one set of scenarios run against each backend.

The shared tests take the module-scoped ``backend`` fixture, parametrised over ``ray`` (a
local two-node Ray cluster: a head without CPUs + one 2-CPU node) and ``dask`` (a local Dask
cluster of two single-threaded worker processes). Pytest groups the tests by that fixture's
parameter, so each cluster starts once: every ``ray`` case runs, the Ray cluster is torn
down, then every ``dask`` case runs. The lost-cluster scenario is defined last so that it
runs last for each backend (it loses the cluster, then puts one back). A backend whose
package is missing is skipped. Backend-specific tests are plain tests; those that need no
cluster are defined first, so they run before either cluster starts.
"""

from __future__ import annotations

import os
import signal
import sys
import threading

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.errors import ClusterError, InputError
from evomotion.run.config import resolve_config
from evomotion.run.evaluators import make_evaluator
from evomotion.run.runner import run_study
from evomotion.studies import get_study

sys.path.insert(0, os.path.dirname(__file__))
from cluster_helpers import (  # noqa: E402
    HERE,
    CrashConfig,
    CrashProblem,
    assert_same_evaluation,
    assert_same_run,
    serial_evaluation,
)
from toy_study import STUDY as TOY  # noqa: E402

BACKENDS = ("ray", "dask")  # this order: all ray cases run, then all dask cases
RAY_HEALTH = {"health_check_period_ms": 500, "health_check_failure_threshold": 3,
              "health_check_initial_delay_ms": 0}


def _kill_later(pid: int, delay_s: float) -> int:
    threading.Timer(delay_s, os.kill, (pid, signal.SIGKILL)).start()
    return pid


class RayBackend:
    """A head without CPUs + one 2-CPU worker node; the test process is the Ray driver."""

    name = "ray"
    lost_message = "lost the Ray cluster"
    poison_kw = {"max_attempts": 2}  # a chunk may kill two workers before it is marked worst

    def __init__(self) -> None:
        import ray
        from ray.cluster_utils import Cluster

        from evomotion.run.ray_evaluator import RayEvaluator

        self.ray, self.evaluator = ray, RayEvaluator
        self.cluster = Cluster(initialize_head=True, head_node_args={
            "num_cpus": 0, "include_dashboard": False, "_system_config": RAY_HEALTH})
        self.cluster.add_node(num_cpus=2)
        path = os.pathsep.join([str(HERE), os.environ.get("PYTHONPATH", "")])
        ray.init(address=self.cluster.address, logging_level="ERROR", log_to_driver=False,
                 runtime_env={"env_vars": {"PYTHONPATH": path}})
        self.address = ""  # evaluators use the driver's connection to the cluster
        self.overrides = ["run.evaluator='ray'", "run.workers=2"]
        self.cli_args = ["--evaluator", "ray", "--workers", "2"]

    def make(self, make_problem, cfg, **kw):
        return self.evaluator(make_problem, cfg, workers=2, **kw)

    def worker_count(self, ev) -> int:
        return len(ev.actors)

    def worker_env(self, ev, key: str) -> list[str | None]:
        return self.ray.get([a.environ.remote(key) for a in ev.actors])

    def kill_one_worker(self, ev, delay_s: float = 0.1) -> int:
        """SIGKILL one actor's process ``delay_s`` from now; its pid."""
        return _kill_later(ev.worker_pids()[0], delay_s)

    def assert_worker_replaced(self, ev, pid: int, log: str) -> None:
        assert ev.replaced == 1 and ev.failed_chunks == 0
        assert "replaced, chunk re-run" in log  # it died while running a chunk

    def assert_poisoned_counts(self, ev) -> None:
        assert ev.failed_chunks == 1 and ev.replaced == 2

    def lose_cluster(self) -> None:
        for node in list(self.cluster.worker_nodes):
            self.cluster.remove_node(node)

    def restore(self) -> None:
        self.cluster.add_node(num_cpus=2)

    def close(self) -> None:
        self.ray.shutdown()
        self.cluster.shutdown()


def _local_dask_cluster(n: int = 2):
    from distributed import LocalCluster

    return LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                        dashboard_address="127.0.0.1:0", silence_logs=50)


class DaskBackend:
    """A local Dask cluster of two single-threaded worker processes, used by address."""

    name = "dask"
    lost_message = "lost the Dask scheduler"
    poison_kw: dict = {}  # allowed-failures=1: a chunk may kill two workers (see _start)

    def __init__(self) -> None:
        from evomotion.run.dask_evaluator import DaskEvaluator

        self.evaluator = DaskEvaluator
        self._start()

    def _start(self) -> None:
        import dask

        with dask.config.set({"distributed.scheduler.allowed-failures": 1}):
            self.cluster = _local_dask_cluster()
        self.address = self.cluster.scheduler_address

    @property
    def overrides(self) -> list[str]:
        return ["run.evaluator='dask'", f"run.address={self.address!r}"]

    @property
    def cli_args(self) -> list[str]:
        return ["--evaluator", "dask", "--address", self.address]

    def make(self, make_problem, cfg, **kw):
        return self.evaluator(make_problem, cfg, address=self.address, **kw)

    def worker_count(self, ev) -> int:
        return ev.threads

    def worker_env(self, ev, key: str) -> list[str | None]:
        from evomotion.run.dask_evaluator import worker_environ

        return sorted(ev.client.run(worker_environ, key).values())

    def kill_one_worker(self, ev, delay_s: float = 0.1) -> int:
        """SIGKILL one worker process ``delay_s`` from now; its pid."""
        return _kill_later(next(iter(ev.client.run(os.getpid).values())), delay_s)

    def assert_worker_replaced(self, ev, pid: int, log: str) -> None:
        from distributed import Client

        with Client(self.address) as client:  # the nanny replaced the killed worker process
            pids = set(client.run(os.getpid).values())
        assert len(pids) == 2 and pid not in pids

    def assert_poisoned_counts(self, ev) -> None:
        pass  # the scheduler keeps no such counters

    def lose_cluster(self) -> None:
        self.cluster.close()

    def restore(self) -> None:
        self._start()  # a fresh cluster at a new address

    def close(self) -> None:
        self.cluster.close()


@pytest.fixture(scope="module", params=BACKENDS)
def backend(request):
    pytest.importorskip({"ray": "ray", "dask": "distributed"}[request.param])
    b = {"ray": RayBackend, "dask": DaskBackend}[request.param]()
    yield b
    b.close()


# -- backend-specific tests that need no shared cluster (they run first) ------------------


def test_missing_ray_is_a_one_line_input_error(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # "import ray" now fails
    with pytest.raises(InputError, match=r"pip install 'evomotion\[ray\]'"):
        make_evaluator("ray", TOY.make_problem, TOY.problem_config())


def test_missing_dask_is_a_one_line_input_error(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # "import distributed" now fails
    with pytest.raises(InputError, match=r"pip install 'evomotion\[dask\]'"):
        make_evaluator("dask", TOY.make_problem, TOY.problem_config())


def test_dask_unreachable_scheduler_is_a_clear_error():
    pytest.importorskip("distributed")
    from evomotion.run.dask_evaluator import DaskEvaluator

    with pytest.raises(ClusterError, match="cannot reach the Dask scheduler"):
        DaskEvaluator(TOY.make_problem, TOY.problem_config(), address="tcp://127.0.0.1:9",
                      start_timeout_s=1.0)


def test_dask_local_cluster_when_no_address():
    pytest.importorskip("distributed")
    from evomotion.run.dask_evaluator import worker_environ

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


# -- scenarios shared by both backends ------------------------------------------------------


def test_any_batch_and_chunking_matches_serial(backend):
    """Order, NaN flags and isolated exceptions survive any split into chunks."""
    ev = backend.make(TOY.make_problem, TOY.problem_config())

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


def test_toy_run_identical_to_serial(backend, tmp_path):
    """NaN fitness, raising batches and chunking all give the serial result, bit for bit."""
    cfg_s = resolve_config(TOY, None, ["run.generations=5"])
    cfg_b = resolve_config(TOY, None, ["run.generations=5", *backend.overrides,
                                       "run.chunks_per_worker=3"])
    run_study(TOY, cfg_s, tmp_path / "serial", quiet=True)
    run_study(TOY, cfg_b, tmp_path / backend.name, quiet=True)
    assert_same_run(tmp_path / "serial", tmp_path / backend.name)


def test_functions_generation_and_worker_env(backend):
    """``workers=0``: one worker per CPU of the cluster, each with OMP_NUM_THREADS=1."""
    study = get_study("functions")
    cfg = resolve_config(study, None, ["problem.name=rastrigin", "problem.dim=12"]).problem
    genomes = study.make_problem(cfg).genome.sample(np.random.default_rng(4), 101)
    ev = make_evaluator(backend.name, study.make_problem, cfg, workers=0, chunks_per_worker=4,
                        address=backend.address)
    try:
        assert backend.worker_count(ev) == 2
        assert backend.worker_env(ev, "OMP_NUM_THREADS") == ["1", "1"]
        assert_same_evaluation(ev(genomes), serial_evaluation(study, cfg, genomes))
    finally:
        ev.close()


def test_humanoid_step_generation_identical_to_serial(backend):
    study = get_study("humanoid-step")
    cfg = resolve_config(study, None, []).problem
    genomes = study.make_problem(cfg).genome.sample(np.random.default_rng(1), 8)
    ev = backend.make(study.make_problem, cfg, chunks_per_worker=2)
    try:
        assert_same_evaluation(ev(genomes), serial_evaluation(study, cfg, genomes))
    finally:
        ev.close()


def test_grid_path_run_identical_to_serial(backend, tmp_path):
    """The grid-path problem through the generic ask/tell loop (its default cGA): the study's
    own driver evaluates in-process and does not take an evaluator."""
    study = get_study("grid-path")
    for name in ("serial", backend.name):
        cfg = resolve_config(study, None, ["run.generations=6", *backend.overrides,
                                           f"run.evaluator={name!r}"])
        run_study(study, cfg, tmp_path / name, quiet=True)
    assert_same_run(tmp_path / "serial", tmp_path / backend.name)


def test_policy_search_optimizers_identical_to_serial(backend, tmp_path):
    """Every policy-search optimizer (ARS, OpenAI-ES, PGPE, SNES, CMA-ES) through the gym study,
    and the NAO closed loop of humanoid-balance: the normaliser and the episode seeds travel in
    the rows, so the cluster gives the serial run bit for bit."""
    pytest.importorskip("gymnasium")
    from evomotion.studies.gym.study import POLICY_OPTIMIZERS

    gym = get_study("gym")
    base = ["problem.max_episode_steps=20", "problem.eval_episodes=2", "run.generations=3",
            "run.seed=3", "algorithm.pop_size=6"]
    for opt in POLICY_OPTIMIZERS:
        extra = ["algorithm.top_directions=0"] if opt == "ars" else []
        for name in ("serial", backend.name):
            over = [*base, f"algorithm.name={opt}", *extra, f"run.evaluator={name}"]
            if name != "serial":
                over += backend.overrides
            run_study(gym, resolve_config(gym, None, over), tmp_path / opt / name, quiet=True)
        assert_same_run(tmp_path / opt / "serial", tmp_path / opt / backend.name)
    balance = get_study("humanoid-balance")
    for name in ("serial", backend.name):
        over = [*balance.smoke, "run.generations=2", f"run.evaluator={name}"]
        if name != "serial":
            over += backend.overrides
        run_study(balance, resolve_config(balance, None, over), tmp_path / "bal" / name,
                  quiet=True)
    assert_same_run(tmp_path / "bal" / "serial", tmp_path / "bal" / backend.name)


def test_worker_killed_mid_generation_run_completes_identically(backend, tmp_path,
                                                                monkeypatch, caplog):
    overrides = ["run.generations=4", "problem.sleep_s=0.1", "problem.raise_above=9"]
    run_study(TOY, resolve_config(TOY, None, overrides), tmp_path / "serial", quiet=True)
    seen = {"calls": 0}
    original = backend.evaluator.__call__

    def call(self, genomes):
        seen["ev"], seen["calls"] = self, seen["calls"] + 1
        if seen["calls"] == 3:  # SIGKILL one worker while generation 2's chunks run
            seen["pid"] = backend.kill_one_worker(self)
        return original(self, genomes)

    monkeypatch.setattr(backend.evaluator, "__call__", call)
    cfg = resolve_config(TOY, None, [*overrides, *backend.overrides, "run.chunks_per_worker=3"])
    res = run_study(TOY, cfg, tmp_path / backend.name, quiet=True)
    assert res.stop_reason == "generations" and seen["calls"] == 5
    backend.assert_worker_replaced(seen["ev"], seen["pid"], caplog.text)
    assert_same_run(tmp_path / "serial", tmp_path / backend.name)


def test_chunk_that_keeps_killing_workers_is_marked_worst(backend):
    cfg = CrashConfig()
    genomes = np.random.default_rng(2).uniform(-0.9, 0.9, (12, cfg.dim))
    genomes[7, 0] = 0.99  # rows 6-8 form the poisoned chunk (4 chunks of 3)
    ev = backend.make(CrashProblem, cfg, chunks_per_worker=2, **backend.poison_kw)
    try:
        out = ev(genomes)
        backend.assert_poisoned_counts(ev)
        bad = np.zeros(12, bool)
        bad[6:9] = True
        np.testing.assert_array_equal(out.failed, bad)
        assert np.all(out.fitness[bad] == np.inf)
        good = (genomes[~bad] ** 2).sum(1)
        assert out.fitness[~bad].tobytes() == good.tobytes()
        assert len(out.errors) == 1 and "rows 6-8" in out.errors[0]
        again = ev(genomes[:6])  # the replaced workers go on evaluating
        assert again.fitness.tobytes() == good[:6].tobytes()
    finally:
        ev.close()


# -- backend-specific tests on the shared cluster -------------------------------------------


# Pytest groups the module-scoped fixture's tests by the parameter's index: "ray" is index 0
# here as in BACKENDS, so this runs among the other ray cases, on the same cluster.
@pytest.mark.parametrize("backend", ["ray"], indirect=True)
def test_ray_more_workers_than_cluster_cpus_is_a_clear_error(backend):
    with pytest.raises(ClusterError, match="has 2 CPUs; cannot start 3"):
        backend.evaluator(TOY.make_problem, TOY.problem_config(), workers=3)


# -- last for each backend: it loses the cluster, then puts one back ------------------------


def test_losing_the_cluster_checkpoints_and_serial_resume_is_identical(backend, tmp_path,
                                                                      monkeypatch, capsys):
    from evomotion.cli import main

    sets = ["--set", "problem.dim=6", "--set", "run.generations=8",
            "--set", "algorithm.pop_size=40", "--set", "run.checkpoint_every=100"]
    with pytest.raises(SystemExit) as done:
        main(["evomotion", "run", "functions", "-q", "--out", str(tmp_path / "serial"), *sets])
    assert done.value.code == 0
    calls = {"n": 0}
    original = backend.evaluator.__call__

    def call(self, genomes):
        calls["n"] += 1
        if calls["n"] == 4:
            self.start_timeout_s, self.poll_s = 2.0, 0.2  # give up on the lost cluster quickly
            backend.lose_cluster()
        return original(self, genomes)

    monkeypatch.setattr(backend.evaluator, "__call__", call)
    out = tmp_path / "lost"
    try:
        with pytest.raises(SystemExit) as lost:
            main(["evomotion", "run", "functions", "-q", "--out", str(out),
                  *backend.cli_args, *sets])
    finally:
        backend.restore()
    assert lost.value.code == 4  # a ClusterError
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("error:")]
    assert len(err) == 1 and backend.lost_message in err[0] and "evomotion resume" in err[0]
    log = (out / "log.txt").read_text()
    assert "run failed at generation 2" in log and "resume" in log
    assert (out / "checkpoints" / "latest.json").exists()
    with pytest.raises(SystemExit) as done:
        main(["evomotion", "resume", str(out), "-q", "--evaluator", "serial"])
    assert done.value.code == 0
    assert_same_run(tmp_path / "serial", out)
