"""The studio's data layer and actions, without a server."""

from __future__ import annotations

import json
import os
import shutil
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.errors import InputError
from evomotion.run.config import resolve_config
from evomotion.run.history import read_history
from evomotion.run.runner import run_study
from evomotion.studies import get_study
from evomotion.studio import actions, data, form_schema

FN = ["problem.dim=4", "algorithm.pop_size=10"]


def _run(root, name, *extra, generations=8):
    s = get_study("functions")
    cfg = resolve_config(s, None, [*FN, f"run.generations={generations}", *extra])
    run_study(s, cfg, root / name, quiet=True)
    return root / name


def test_finished_run_is_listed_with_its_last_row(tmp_path):
    _run(tmp_path, "a")
    (r,) = data.list_runs(tmp_path)
    assert (r.name, r.study, r.status, r.stop_reason) == ("a", "functions", "finished",
                                                          "generations")
    assert r.generation == 8 and r.evaluations > 0 and np.isfinite(r.best)
    assert not r.resumable and data.list_runs(tmp_path, "arm-ik") == []


def _lock(pid, host=None, start=None):
    from evomotion.run.lock import boot_id, process_start

    return json.dumps({"pid": pid, "host": host or socket.gethostname(),
                       "start": process_start(pid) if start is None else start,
                       "boot": boot_id(), "command": "evomotion"}) + "\n"


def _exec_done(pid: int, timeout_s: float = 30.0) -> None:
    """Wait until the child ``pid`` runs its own command line (until its exec, /proc shows
    the parent's: a busy machine, e.g. a parallel test run, leaves a moment between)."""
    import time

    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        try:
            if b"evomotion" in Path(f"/proc/{pid}/cmdline").read_bytes():
                return
        except OSError:
            pass
        time.sleep(0.01)


def test_status_from_lock_and_log(tmp_path):
    d = _run(tmp_path, "a")
    # a live process that is an evomotion command line, named with its start time: running
    live = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)", "evomotion"])
    try:
        _exec_done(live.pid)
        (d / "run.lock").write_text(_lock(live.pid))
        assert data.run_status(d) == ("running", "", live.pid)
        assert not data.summarize(tmp_path, d).resumable
    finally:
        live.kill()
        live.wait()
    # the process is gone (kill -9): the lock is stale, the run resumable
    status, detail, pid = data.run_status(d)
    assert (status, pid) == ("stale", None) and f"pid {live.pid}" in detail
    assert "stale" in detail and data.summarize(tmp_path, d).resumable
    (d / "run.lock").write_text("")
    with open(d / "log.txt", "a") as fh:
        fh.write("resumed at generation 8 with evaluator serial\n")
    assert data.run_status(d)[:2] == ("interrupted", "no end logged")
    with open(d / "log.txt", "a") as fh:
        fh.write("run failed at generation 9: ValueError: boom\n")
    assert data.run_status(d)[0] == "failed"
    with open(d / "log.txt", "a") as fh:
        fh.write("stopped: interrupted at generation 9 after 90 evaluations\n")
    assert data.run_status(d)[:2] == ("interrupted", "interrupted")


def test_stats_tail_reads_only_what_was_appended_and_restarts_after_a_cut(tmp_path):
    p = tmp_path / "stats.csv"
    p.write_text("generation,best_so_far\n0,5.0\n1,4.0\n2,3")  # the last row is half written
    t = data.StatsTail(p)
    assert t.update() == 2 and t.column("best_so_far") == [5.0, 4.0]
    with open(p, "a") as fh:
        fh.write(".5\n3,nan\n")
    assert t.update() == 2 and t.column("best_so_far") == [5.0, 4.0, 3.5, None]
    p.write_text("generation,best_so_far\n0,9.0\n")  # cut back by a resume
    assert t.update() == 1 and t.column("generation") == [0.0]


def test_compare_median_and_band(tmp_path):
    runs = [_run(tmp_path, f"r{i}", f"run.seed={i}") for i in range(5)]
    c = data.compare_runs(runs, points=50)
    assert len(c["evaluations"]) == len(c["median"]) > 10
    q25, med, q75 = (np.array(c[k]) for k in ("q25", "median", "q75"))
    assert (q25 <= med).all() and (med <= q75).all()
    assert (np.diff(med) <= 1e-12).all()  # best so far of a minimisation never rises
    assert max(c["runs"]) == 5


def test_nothing_outside_the_runs_folder(tmp_path):
    d = _run(tmp_path / "runs", "a")
    (tmp_path / "secret.txt").write_text("x")
    os.symlink(tmp_path / "secret.txt", d / "link.txt")
    for bad in ("../secret.txt", "a/../../secret.txt", "/etc/passwd", "a/link.txt"):
        with pytest.raises(InputError):
            data.safe_file(tmp_path / "runs", bad)
    assert data.safe_file(tmp_path / "runs", "a/stats.csv").name == "stats.csv"
    for bad in ("..", ".", "", "a/checkpoints", "../runs/a/.."):
        with pytest.raises(InputError):
            data.resolve_run(tmp_path / "runs", bad)


@settings(max_examples=60, deadline=None)
@given(st.text(max_size=40))
def test_any_requested_path_stays_inside(tmp_path_factory, rel):
    root = tmp_path_factory.mktemp("r")
    (root / "f.txt").write_text("x")
    try:
        p = data.safe_file(root, rel)
    except (InputError, ValueError, OSError):
        return
    assert p.resolve().is_relative_to(root.resolve())


def test_form_fields_and_one_line_errors():
    fields = actions.form_fields("functions")
    keys = [f.key for f in fields]
    assert "run.seed" in keys and "problem.dim" in keys and "algorithm.name" not in keys
    assert actions.changed_sets(fields, {"run.seed": "3", "problem.name": "rastrigin"}) == \
        ["run.seed=3", 'problem.name="rastrigin"']
    with pytest.raises(InputError) as e:
        actions.check_new_run("functions", None, ["algorithm.pop_size=-4"])
    assert form_schema.field_of_error(str(e.value), keys) == "algorithm.pop_size"
    assert actions.run_command("functions", "paper", ["run.seed=1"], tmp := "out")[-3:] == \
        ["--out", tmp, "--quiet"]
    for name in ("arm-ik", "grid-path", "quadruped-plan", "humanoid-step"):
        assert actions.form_fields(name, "paper")  # every study's schema makes a form
    shown = {f.key: f.shown for f in actions.form_fields("humanoid-walk", robot="dm-humanoid")}
    assert shown["problem.sway_m"] == "0.008" and shown["problem.vx_min"] == "0.15"
    assert shown["problem.robot"] == "dm-humanoid" and shown["problem.symmetric"] == "false"
    nao = {f.key: f.shown for f in actions.form_fields("humanoid-walk")}
    op3 = {f.key: f.shown for f in actions.form_fields("humanoid-walk", robot="op3")}
    assert nao["problem.symmetric"] == "true" and op3["problem.symmetric"] == "false"


def test_history_records_every_generation_and_survives_resume(tmp_path):
    s = get_study("functions")
    cfg = resolve_config(s, None, [*FN, "run.generations=9", "run.history_every=1",
                                   "run.checkpoint_every=3"])
    run_study(s, cfg, tmp_path / "full", quiet=True)
    hist = read_history(tmp_path / "full" / "population.bin")
    assert [g for g, _, _ in hist] == list(range(10))
    assert all(p.shape == (10, 4) and f.shape == (10,) for _, p, f in hist)
    from evomotion.run.faults import fault_at

    with fault_at(5):
        run_study(s, cfg, tmp_path / "cut", quiet=True)
    run_study(s, cfg, tmp_path / "cut", quiet=True, resume=True)
    a = (tmp_path / "full" / "population.bin").read_bytes()
    assert (tmp_path / "cut" / "population.bin").read_bytes() == a
    (tmp_path / "cut" / "population.bin").write_bytes(a[:-5])  # a crash mid-record
    assert len(read_history(tmp_path / "cut" / "population.bin")) == 9
    from evomotion.errors import FileFormatError

    for header in ([0, 0, 1e20], [0, -1, 3], [0, 2.5, 3], [0, np.nan, 1], [0, 1e10, 1e10]):
        bad = tmp_path / "bad.bin"
        np.array(header, "<f8").tofile(bad)
        with pytest.raises(FileFormatError, match="expected a header"):
            read_history(bad)


def test_heat_map_cells_take_the_best_over_the_hidden_measure():
    from types import SimpleNamespace

    from evomotion.studio.archive_map import map_cells

    # a 2 x 2 x 2 grid on [0, 1]^3: two elites share the (x, y) bin (0, 1)
    centre = np.array([[0.25, 0.75, 0.25], [0.25, 0.75, 0.75], [0.75, 0.25, 0.25]])
    a = SimpleNamespace(lower=np.zeros(3), upper=np.ones(3), bins=np.array([2, 2, 2]),
                        centre=centre, objective=np.array([-3.0, -1.0, -2.0]),
                        cell=np.array([2, 6, 1]), measures=centre,
                        measure_names=("a", "b", "c"))

    def cells(k=None):
        return [[m.ix, m.iy, m.objective, m.cell] for m in map_cells(a, set(), None, k)]

    assert cells() == [[0, 1, -1.0, 6], [1, 0, -2.0, 1]]
    assert cells(0) == [[0, 1, -3.0, 2], [1, 0, -2.0, 1]]
    assert cells(1) == [[0, 1, -1.0, 6]]


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=400))
def test_population_bin_reader_never_crashes(tmp_path_factory, raw):
    from evomotion.errors import FileFormatError

    p = tmp_path_factory.mktemp("h") / "population.bin"
    p.write_bytes(raw)
    try:
        hist = read_history(p)
    except FileFormatError as e:
        assert str(e).startswith(str(p)) and "\n" not in str(e)
        return
    for g, pop, fit in hist:
        assert pop.ndim == 2 and fit.shape == (pop.shape[0],) and isinstance(g, int)


def test_compare_groups_runs_by_study_and_never_pools_them(tmp_path):
    """Issue 35: runs of different studies were pooled into one band; now one group per study
    (in the order first selected), each with its runs' own curves."""
    a = [_run(tmp_path, f"f{i}", f"run.seed={i}") for i in range(2)]
    (tmp_path / "other").mkdir()
    other = tmp_path / "other" / "g0"
    shutil.copytree(a[0], other)
    cfg = other / "config.toml"
    cfg.write_text(cfg.read_text().replace('study = "functions"', 'study = "grid-path"', 1))
    groups = data.compare_groups([a[0], other, a[1]], points=20, labels=["f0", "other/g0", "f1"])
    assert [g["study"] for g in groups] == ["functions", "grid-path"]
    assert groups[0]["names"] == ["f0", "f1"] and groups[1]["names"] == ["other/g0"]
    assert max(groups[0]["runs"]) == 2 and max(groups[1]["runs"]) == 1  # runs counted per x
    assert [c["run"] for c in groups[0]["curves"]] == ["f0", "f1"]
    c0 = groups[0]["curves"][0]
    assert len(c0["evaluations"]) == len(c0["best"]) > 0


def test_compare_series_keep_internal_series_out_of_the_legend(tmp_path):
    from evomotion.studio.pages import compare_series

    runs = [_run(tmp_path, f"r{i}", f"run.seed={i}") for i in range(2)]
    series, legend = compare_series(data.compare_groups(runs, points=20))
    assert "functions lower" in [s["name"] for s in series]
    assert legend == ["functions: interquartile band", "functions: median of 2", "r0", "r1"]
    assert len({s["color"] for s in series if "color" in s}) == 1  # one study, one colour
