"""The ray evaluator on a local two-node Ray cluster (a head without CPUs + one 2-CPU node).

The cluster starts once for the module; the last test removes its worker node to lose the
whole cluster, then puts a node back.
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

ray = pytest.importorskip("ray")
from ray.cluster_utils import Cluster  # noqa: E402

from evomotion.errors import ClusterError  # noqa: E402
from evomotion.run.config import resolve_config  # noqa: E402
from evomotion.run.evaluators import make_evaluator  # noqa: E402
from evomotion.run.ray_evaluator import RayEvaluator  # noqa: E402
from evomotion.run.runner import run_study  # noqa: E402
from evomotion.studies import STUDIES, get_study  # noqa: E402

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

FAST_HEALTH = {"health_check_period_ms": 500, "health_check_failure_threshold": 3,
               "health_check_initial_delay_ms": 0}


@pytest.fixture(scope="module")
def cluster():
    c = Cluster(initialize_head=True, head_node_args={
        "num_cpus": 0, "include_dashboard": False, "_system_config": FAST_HEALTH})
    c.add_node(num_cpus=2)
    path = os.pathsep.join([str(HERE), os.environ.get("PYTHONPATH", "")])
    ray.init(address=c.address, logging_level="ERROR", log_to_driver=False,
             runtime_env={"env_vars": {"PYTHONPATH": path}})
    yield c
    ray.shutdown()
    c.shutdown()


def _study_or_skip(name: str):
    if name not in STUDIES:
        pytest.skip(f"study {name!r} is not registered yet")
    return get_study(name)


def test_any_batch_and_chunking_matches_serial(cluster):
    """Order, NaN flags and isolated exceptions survive any split into chunks."""
    ev = RayEvaluator(TOY.make_problem, TOY.problem_config(), workers=2)

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


def test_toy_run_identical_to_serial(cluster, tmp_path):
    """NaN fitness, raising batches and chunking all give the serial result, bit for bit."""
    cfg_s = resolve_config(TOY, None, ["run.generations=5"])
    cfg_r = resolve_config(TOY, None, ["run.generations=5", "run.evaluator=ray",
                                       "run.workers=2", "run.chunks_per_worker=3"])
    run_study(TOY, cfg_s, tmp_path / "serial", quiet=True)
    run_study(TOY, cfg_r, tmp_path / "ray", quiet=True)
    assert_same_run(tmp_path / "serial", tmp_path / "ray")


def test_functions_generation_and_worker_env(cluster):
    study = get_study("functions")
    cfg = resolve_config(study, None, ["problem.name=rastrigin", "problem.dim=12"]).problem
    genomes = study.make_problem(cfg).genome.sample(np.random.default_rng(4), 101)
    ev = make_evaluator("ray", study.make_problem, cfg, workers=0, chunks_per_worker=4)
    try:
        assert len(ev.actors) == 2  # one actor per CPU of the cluster
        assert ray.get([a.environ.remote("OMP_NUM_THREADS") for a in ev.actors]) == ["1", "1"]
        assert_same_evaluation(ev(genomes), serial_evaluation(study, cfg, genomes))
    finally:
        ev.close()


def test_more_workers_than_cluster_cpus_is_a_clear_error(cluster):
    with pytest.raises(ClusterError, match="has 2 CPUs; cannot start 3"):
        RayEvaluator(TOY.make_problem, TOY.problem_config(), workers=3)


def test_humanoid_step_generation_identical_to_serial(cluster):
    study = _study_or_skip("humanoid-step")
    cfg = resolve_config(study, None, []).problem
    genomes = study.make_problem(cfg).genome.sample(np.random.default_rng(1), 8)
    ev = RayEvaluator(study.make_problem, cfg, workers=2, chunks_per_worker=2)
    try:
        assert_same_evaluation(ev(genomes), serial_evaluation(study, cfg, genomes))
    finally:
        ev.close()


def test_grid_path_run_identical_to_serial(cluster, tmp_path):
    """The grid-path problem through the generic ask/tell loop (its default cGA): the study's
    own driver evaluates in-process and does not take an evaluator."""
    study = _study_or_skip("grid-path")
    for name in ("serial", "ray"):
        cfg = resolve_config(study, None, ["run.generations=6", f"run.evaluator={name!r}",
                                           "run.workers=2"])
        run_study(study, cfg, tmp_path / name, quiet=True)
    assert_same_run(tmp_path / "serial", tmp_path / "ray")


def test_actor_killed_mid_generation_run_completes_identically(cluster, tmp_path, monkeypatch,
                                                               caplog):
    overrides = ["run.generations=4", "problem.sleep_s=0.1", "problem.raise_above=9"]
    run_study(TOY, resolve_config(TOY, None, overrides), tmp_path / "serial", quiet=True)
    seen = {}
    original = RayEvaluator.__call__

    def call(self, genomes):
        seen["ev"], seen["calls"] = self, seen.get("calls", 0) + 1
        if seen["calls"] == 3:  # SIGKILL one actor while generation 2's chunks run
            pid = self.worker_pids()[0]
            threading.Timer(0.1, os.kill, (pid, signal.SIGKILL)).start()
        return original(self, genomes)

    monkeypatch.setattr(RayEvaluator, "__call__", call)
    cfg = resolve_config(TOY, None, [*overrides, "run.evaluator='ray'", "run.workers=2",
                                     "run.chunks_per_worker=3"])
    res = run_study(TOY, cfg, tmp_path / "ray", quiet=True)
    assert res.stop_reason == "generations"
    assert seen["ev"].replaced == 1 and seen["ev"].failed_chunks == 0
    assert "replaced, chunk re-run" in caplog.text  # it died while running a chunk
    assert_same_run(tmp_path / "serial", tmp_path / "ray")


def test_chunk_that_keeps_killing_workers_is_marked_worst(cluster):
    cfg = CrashConfig()
    genomes = np.random.default_rng(2).uniform(-0.9, 0.9, (12, cfg.dim))
    genomes[7, 0] = 0.99  # rows 6-8 form the poisoned chunk (4 chunks of 3)
    ev = RayEvaluator(CrashProblem, cfg, workers=2, chunks_per_worker=2, max_attempts=2)
    try:
        out = ev(genomes)
        assert ev.failed_chunks == 1 and ev.replaced == 2
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


def test_losing_the_cluster_checkpoints_and_serial_resume_is_identical(cluster, tmp_path,
                                                                      monkeypatch, capsys):
    """Runs last: removes the only worker node mid-run, then adds a fresh one back."""
    from evomotion.cli import main

    sets = ["--set", "problem.dim=6", "--set", "run.generations=8",
            "--set", "algorithm.pop_size=40", "--set", "run.checkpoint_every=100"]
    with pytest.raises(SystemExit) as done:
        main(["evomotion", "run", "functions", "-q", "--out", str(tmp_path / "serial"), *sets])
    assert done.value.code == 0
    calls = {"n": 0}
    original = RayEvaluator.__call__

    def call(self, genomes):
        calls["n"] += 1
        if calls["n"] == 4:
            self.start_timeout_s, self.poll_s = 2.0, 0.2  # give up on replacements quickly
            for node in list(cluster.worker_nodes):
                cluster.remove_node(node)
        return original(self, genomes)

    monkeypatch.setattr(RayEvaluator, "__call__", call)
    out = tmp_path / "lost"
    try:
        with pytest.raises(SystemExit) as lost:
            main(["evomotion", "run", "functions", "-q", "--out", str(out),
                  "--evaluator", "ray", "--workers", "2", *sets])
    finally:
        cluster.add_node(num_cpus=2)
    assert lost.value.code == 4
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("error:")]
    assert len(err) == 1 and "lost the Ray cluster" in err[0] and "evomotion resume" in err[0]
    log = (out / "log.txt").read_text()
    assert "run failed at generation 2" in log and "resume" in log
    assert (out / "checkpoints" / "latest.json").exists()
    with pytest.raises(SystemExit) as done:
        main(["evomotion", "resume", str(out), "-q", "--evaluator", "serial"])
    assert done.value.code == 0
    assert_same_run(tmp_path / "serial", out)


def test_missing_ray_is_a_one_line_input_error(monkeypatch):
    from evomotion.errors import InputError

    monkeypatch.setitem(sys.modules, "ray", None)  # "import ray" now fails
    with pytest.raises(InputError, match=r"pip install 'evomotion\[ray\]'"):
        make_evaluator("ray", TOY.make_problem, TOY.problem_config())
