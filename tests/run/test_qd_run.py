"""Quality-diversity optimizers through the one run loop: QD columns, archive.npz, plots,
process evaluator and resume bit-identical (the archive included)."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.run.archive_file import read_archive
from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.run.stats import read_stats
from evomotion.studies import get_study

STUDY = get_study("functions")
BASE = ["problem.dim=6", "problem.measures=linear_projection", "run.generations=12",
        "run.checkpoint_every=4"]
QD_SETTINGS = {
    "cma_me": ["algorithm.name=cma_me", "algorithm.emitters=3", "algorithm.pop_size=10",
               "algorithm.bins=20"],
    "cma_mae": ["algorithm.name=cma_me", "algorithm.emitters=3", "algorithm.pop_size=10",
                "algorithm.learning_rate=0.05", "algorithm.threshold_min=-200",
                "algorithm.ranking=imp", "algorithm.restart_rule=basic",
                "algorithm.archive=cvt", "algorithm.cells=100", "algorithm.cvt_samples=5000"],
    "map_elites": ["algorithm.name=map_elites", "algorithm.pop_size=20", "algorithm.bins=20"],
}


def _archive_equal(a, b) -> None:
    for k in ("cell", "solution", "objective", "measures", "all_centres"):
        np.testing.assert_array_equal(getattr(a, k), getattr(b, k), err_msg=k)


@pytest.mark.parametrize("name", sorted(QD_SETTINGS))
def test_qd_run_writes_columns_archive_and_plots(tmp_path, name):
    cfg = resolve_config(STUDY, None, BASE + QD_SETTINGS[name])
    res = run_study(STUDY, cfg, tmp_path, quiet=True)
    assert res.exit_code == 0
    s = read_stats(tmp_path / "stats.csv")
    for col in ("archive_size", "coverage", "qd_score", "qd_best"):
        assert col in s
    assert np.all(np.diff(s["archive_size"]) >= 0)  # the result archive is elitist
    assert s["coverage"][-1] > s["coverage"][0] > 0
    a = read_archive(tmp_path / "archive.npz")
    assert a.cell.size == s["archive_size"][-1]
    np.testing.assert_allclose(a.objective.max(), s["qd_best"][-1])
    # every elite sits in its cell: its recomputed measures are the stored ones
    from evomotion.studies.functions.problem import linear_projection

    np.testing.assert_allclose(linear_projection(a.solution), a.measures)
    for p in ("plots/qd.png", "plots/archive.png", "plots/fitness.png"):
        assert (tmp_path / p).stat().st_size > 1000


@pytest.mark.parametrize("name", sorted(QD_SETTINGS))
def test_qd_resume_after_interrupt_is_bit_identical(tmp_path, monkeypatch, name):
    cfg = resolve_config(STUDY, None, BASE + QD_SETTINGS[name])
    run_study(STUDY, cfg, tmp_path / "full", quiet=True)
    from evomotion.run import evaluators

    calls = {"n": 0}
    orig = evaluators.SerialEvaluator.__call__

    def interrupting(self, genomes):
        calls["n"] += 1
        if calls["n"] == 7:
            raise KeyboardInterrupt
        return orig(self, genomes)

    monkeypatch.setattr(evaluators.SerialEvaluator, "__call__", interrupting)
    assert run_study(STUDY, cfg, tmp_path / "cut", quiet=True).stop_reason == "interrupted"
    monkeypatch.setattr(evaluators.SerialEvaluator, "__call__", orig)
    run_study(STUDY, cfg, tmp_path / "cut", quiet=True, resume=True)
    s1, s2 = read_stats(tmp_path / "full" / "stats.csv"), read_stats(tmp_path / "cut" /
                                                                       "stats.csv")
    for col in ("best", "mean", "archive_size", "qd_score", "qd_best"):
        np.testing.assert_array_equal(s1[col], s2[col], err_msg=col)
    _archive_equal(read_archive(tmp_path / "full" / "archive.npz"),
                   read_archive(tmp_path / "cut" / "archive.npz"))


def test_process_evaluator_gives_the_same_archive(tmp_path):
    settings = BASE + QD_SETTINGS["cma_me"]
    run_study(STUDY, resolve_config(STUDY, None, settings), tmp_path / "s", quiet=True)
    run_study(STUDY, resolve_config(STUDY, None, settings + [
        "run.evaluator=process", "run.workers=2"]), tmp_path / "p", quiet=True)
    _archive_equal(read_archive(tmp_path / "s" / "archive.npz"),
                   read_archive(tmp_path / "p" / "archive.npz"))


def test_qd_optimizer_on_a_problem_without_measures_is_one_line(tmp_path):
    cfg = resolve_config(STUDY, None, ["problem.dim=4", "algorithm.name=map_elites"])
    with pytest.raises(InputError, match="needs a problem with measures"):
        run_study(STUDY, cfg, tmp_path, quiet=True)


@pytest.mark.parametrize("item,key", [
    ("algorithm.learning_rate=0.5", "threshold_min"),
    ("algorithm.archive=hex", "algorithm.archive"),
    ("algorithm.ranking=best", "algorithm.ranking"),
    ("algorithm.emitters=0", "algorithm.emitters"),
])
def test_bad_qd_settings_name_the_key(tmp_path, item, key):
    with pytest.raises((InputError, ValueError), match=key):
        cfg = resolve_config(STUDY, None, BASE + ["algorithm.name=cma_me", item])
        run_study(STUDY, cfg, tmp_path, quiet=True)


def test_read_archive_refuses_bad_files(tmp_path):
    bad = tmp_path / "archive.npz"
    bad.write_bytes(b"not a zip")
    with pytest.raises(InputError, match="archive.npz"):
        read_archive(bad)
    np.savez(bad, kind=np.array("grid"))
    with pytest.raises(InputError, match="missing field"):
        read_archive(bad)
    with pytest.raises(InputError, match="no such file"):
        read_archive(tmp_path / "none.npz")
