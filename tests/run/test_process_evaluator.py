"""The process evaluator survives its workers: segfaults, SIGKILL and a killed parent.

A worker that dies is replaced and the chunk it was running re-run; a chunk that keeps
killing workers is split down to the individual, which gets the worst fitness; everything
else stays bit-identical to ``serial``. Workers end with their parent, even on ``kill -9``.
The problem is ``segfault_study.SegfaultProblem`` (SIGSEGV for ``x[0] > poison_above``);
its ``mode="nan"`` gives the serial reference for the same genomes.
"""

from __future__ import annotations

import json
import os
import select
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from evomotion.errors import ClusterError
from evomotion.run.config import resolve_config
from evomotion.run.evaluators import ProcessEvaluator, SerialEvaluator
from evomotion.run.runner import run_study

sys.path.insert(0, os.path.dirname(__file__))
from cluster_helpers import HERE, assert_same_evaluation  # noqa: E402
from segfault_study import STUDY, SegfaultConfig, SegfaultProblem  # noqa: E402

SRC = Path(__file__).resolve().parents[2] / "src"


def _genomes(n: int, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-4.0, 4.0, (n, SegfaultConfig.dim))


def _serial(genomes: np.ndarray, **kw):
    return SerialEvaluator(SegfaultProblem, SegfaultConfig(mode="nan", **kw))(genomes)


def test_segfaulting_rows_get_the_worst_fitness_and_the_rest_matches_serial(caplog):
    genomes = _genomes(16)
    genomes[[7, 12], 0] = [4.9, 4.8]  # chunks of 4: rows 4-7 and 12-15 are poisoned
    ev = ProcessEvaluator(SegfaultProblem, SegfaultConfig(), workers=2, chunks_per_worker=2)
    try:
        out = ev(genomes)
        ref = _serial(genomes)
        assert out.errors == [
            f"worker died (signal SIGSEGV) evaluating row {r}; it gets the worst fitness"
            for r in (7, 12)]
        ref.errors = out.errors
        assert_same_evaluation(out, ref)  # worst fitness, failed and NaN metrics at 7 and 12
        assert np.flatnonzero(out.failed).tolist() == [7, 12]
        assert np.all(out.fitness[[7, 12]] == -np.inf)
        # each poisoned chunk of 4: 2 attempts, then halves of 2, then the individual
        assert ev.failed_rows == 2 and ev.replaced == 8
        assert "rows 4-7; replaced, chunk split in halves" in caplog.text
        pids = ev.worker_pids()
        assert len(pids) == 2 and all(p not in pids for p in (0, os.getpid()))
        again = ev(genomes[:6])  # the replaced workers go on evaluating
        assert_same_evaluation(again, _serial(genomes[:6]))
        assert ev.replaced == 8 and ev.worker_pids() == pids
    finally:
        ev.close()


def test_run_with_segfaulting_genomes_matches_serial_bit_for_bit(tmp_path):
    common = ["run.generations=4", "problem.poison_above=4.0"]
    serial = resolve_config(STUDY, None, [*common, "problem.mode='nan'"])
    proc = resolve_config(STUDY, None, [*common, "run.evaluator='process'", "run.workers=2"])
    run_study(STUDY, serial, tmp_path / "serial", quiet=True)
    res = run_study(STUDY, proc, tmp_path / "process", quiet=True)
    assert res.stop_reason == "generations"
    s_rows, p_rows = (_stats_without_timing(tmp_path / d / "stats.csv")
                      for d in ("serial", "process"))
    assert p_rows == s_rows
    assert sum(int(r["failed"]) for r in p_rows) == 3  # three genomes segfaulted their worker
    best = [json.loads((tmp_path / d / "best.json").read_text()) for d in ("serial", "process")]
    assert best[1] == best[0]
    log = (tmp_path / "process" / "log.txt").read_text()
    assert "worker died (signal SIGSEGV) evaluating row" in log


def _stats_without_timing(path: Path) -> list[dict[str, str]]:
    lines = path.read_text().splitlines()
    head = lines[0].split(",")
    return [{k: v for k, v in zip(head, line.split(","), strict=True)
             if k not in ("wall_s", "evals_per_s")} for line in lines[1:]]


def test_worker_killed_externally_mid_batch_is_replaced_and_batch_matches_serial(caplog):
    genomes = _genomes(12, seed=1)
    ev = ProcessEvaluator(SegfaultProblem, SegfaultConfig(sleep_s=0.3), workers=2,
                          chunks_per_worker=2)
    try:
        victim = ev.worker_pids()[0]
        timer = threading.Timer(0.15, os.kill, (victim, 9))  # SIGKILL during its first chunk
        timer.start()
        out = ev(genomes)
        timer.join()
        assert_same_evaluation(out, _serial(genomes))
        assert ev.replaced >= 1 and ev.failed_rows == 0
        assert victim not in ev.worker_pids()
        assert "(signal SIGKILL) evaluating rows 0-2; replaced, chunk re-run" in caplog.text
    finally:
        ev.close()


def test_problem_that_cannot_be_built_is_a_one_line_error():
    with pytest.raises(ClusterError, match="could not build the problem: AttributeError"):
        ProcessEvaluator(SegfaultProblem, None, workers=1)


PARENT = """
import sys, threading, time
sys.path[:0] = [{src!r}, {here!r}]
import numpy as np
from evomotion.run.evaluators import ProcessEvaluator
from segfault_study import SegfaultConfig, SegfaultProblem
if __name__ == "__main__":
    ProcessEvaluator.die_with_parent = {prctl}
    ev = ProcessEvaluator(SegfaultProblem, SegfaultConfig(sleep_s=120), workers=2)
    line = " ".join(map(str, ev.worker_pids() + ev.worker_guards()))
    threading.Timer(0.3, print, (line,), {{"flush": True}}).start()  # once both are busy
    ev(np.zeros((4, 4)))  # each worker sleeps in its chunk: only the guard can end it
"""


def _gone(pid: int) -> bool:
    """The process has exited (a zombie nobody reaps counts as gone)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] in ("Z", "X")
    except FileNotFoundError:
        return True
    except OSError:  # no /proc: ask the kernel
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        return False


@pytest.mark.parametrize("prctl", [True, False], ids=["prctl", "watchdog"])
def test_workers_end_when_the_parent_is_killed(tmp_path, prctl):
    if prctl and not sys.platform.startswith("linux"):
        pytest.skip("PR_SET_PDEATHSIG is Linux only")
    script = tmp_path / "parent.py"
    script.write_text(textwrap.dedent(PARENT.format(src=str(SRC), here=str(HERE),
                                                    prctl=prctl)))
    parent = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True)
    try:
        ready, _, _ = select.select([parent.stdout], [], [], 60)
        assert ready, "the parent did not start its workers"
        words = parent.stdout.readline().split()
        pids, guards = [int(w) for w in words[:2]], words[2:]
        assert guards == (["prctl"] * 2 if prctl else ["watchdog"] * 2)
        assert not any(_gone(p) for p in pids)
        # busy workers do not read their pipe, so its EOF cannot end them: the guard must
        parent.kill()  # SIGKILL: no cleanup runs in the parent
        parent.wait(10)
        deadline = time.monotonic() + 5.0
        while not all(_gone(p) for p in pids) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert all(_gone(p) for p in pids), f"workers outlived their parent: {pids}"
    finally:
        parent.kill()
        parent.stdout.close()
        parent.wait(10)
