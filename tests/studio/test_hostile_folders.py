"""Hostile run folders cannot block or bloat the studio, and no request name answers 500
(issue 31): a FIFO ``log.txt``, ``problem.robot = "/dev/zero"``, huge sparse files, links to
devices, a folder that does not answer, NUL and control characters in names."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest
from hostile_helpers import fake_run, hostile_root
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.errors import InputError
from evomotion.studio import data, readers

SCRIPT = textwrap.dedent("""
    import json, os, resource, sys, time
    from pathlib import Path
    from evomotion.errors import InputError
    from evomotion.studio import data, nao3d, views
    root = Path(sys.argv[1])
    os.chdir(root)  # relative robot spec paths
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t0 = time.monotonic()
    rows = [r.row() for r in data.list_runs(root)]
    t_list = time.monotonic() - t0
    out = {"rows": rows, "t_list": t_list, "robots": {}, "views": {}}
    for d in sorted(root.iterdir()):
        if not d.is_dir():
            continue
        try:
            out["robots"][d.name] = views.scene_of(d)
        except InputError as e:
            out["robots"][d.name] = "error: " + str(e)
        st = data.StatsTail(d / "stats.csv")
        for _ in range(3):
            st.update()
        data.read_config(d)
        data.log_tail(d)
        views.motions_of(d)
        data.compare_runs([d])
    for scene in ("robot:/dev/zero", "robot:fifo-robot.toml", "robot:huge-robot.toml"):
        try:
            nao3d.load_scene_model(scene)
            out["views"][scene] = "loaded"
        except InputError as e:
            out["views"][scene] = "error: " + str(e)
    out["t_all"] = time.monotonic() - t0
    out["grew_mb"] = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024
    print(json.dumps(out))
""")


def test_hostile_folders_neither_block_nor_bloat(tmp_path):
    root = hostile_root(tmp_path / "runs")
    r = subprocess.run([sys.executable, "-c", SCRIPT, str(root)], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stderr[-3000:]
    out = json.loads(r.stdout)
    assert out["t_list"] < 5 and out["t_all"] < 20, (out["t_list"], out["t_all"])
    assert out["grew_mb"] < 200, out["grew_mb"]
    rows = {row["name"]: row for row in out["rows"]}
    assert set(rows) == {p.name for p in root.iterdir() if p.is_dir()}
    assert rows["fine"]["status"] == "finished" and rows["fine"]["generation"] == 0
    assert rows["fifo-log"]["status"] == "interrupted" and rows["fifo-log"]["generation"] == 0
    for name, scene in out["robots"].items():
        if name.startswith("robot-"):
            assert scene.startswith("error: problem.robot = ") and "\n" not in scene, scene
    assert "character device" in out["robots"]["robot-dev-zero"]
    assert "FIFO" in out["robots"]["robot-fifo-robot.toml"]
    assert "at most" in out["robots"]["robot-huge-robot.toml"]
    assert all(v.startswith("error: ") for v in out["views"].values()), out["views"]


def test_a_folder_that_does_not_answer_is_listed_as_timed_out(tmp_path, monkeypatch):
    fake_run(tmp_path, "fine")
    fake_run(tmp_path, "hung")
    release = threading.Event()
    real = data.summarize
    calls: list[str] = []

    def summarize(root, run_dir):
        calls.append(run_dir.name)
        if run_dir.name == "hung":
            release.wait(30)  # a disk that does not answer
        return real(root, run_dir)

    monkeypatch.setattr(data, "summarize", summarize)
    try:
        for _ in range(3):  # the page refreshes: the hung folder is not asked again
            t0 = time.monotonic()
            rows = {r.name: r for r in data.list_runs(tmp_path, timeout_s=1.0)}
            assert time.monotonic() - t0 < 3.0
            assert rows["fine"].status == "finished"
            hung = rows["hung"]
            assert (hung.status, hung.stop_reason) == ("unreadable", "timed out")
            json.dumps(hung.row(), allow_nan=False)
        assert calls.count("hung") == 1
    finally:
        release.set()
    time.sleep(0.2)
    assert data.list_runs(tmp_path, timeout_s=5)[0].status == "finished"


def test_a_folder_whose_summary_fails_is_one_row(tmp_path, monkeypatch):
    fake_run(tmp_path, "a")
    monkeypatch.setattr(data, "summarize", lambda root, d: 1 / 0)
    (row,) = data.list_runs(tmp_path)
    assert row.status == "unreadable" and "ZeroDivisionError" in row.stop_reason


@pytest.mark.parametrize("name", ["f1\0", "\0", "a\nb", "a\rb", "x" * 5000, "\udcff",
                                  "fine/\0/..", "../fine", "/etc", "fine\x1b[2J"])
def test_bad_names_are_one_input_error(tmp_path, name):
    fake_run(tmp_path, "fine")
    with pytest.raises(InputError) as e:
        data.resolve_run(tmp_path, name)
    assert "\n" not in str(e.value) and "\0" not in str(e.value)
    with pytest.raises(InputError):
        data.safe_file(tmp_path, name + "/stats.csv")


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=60))
def test_any_name_resolves_or_is_refused_in_one_line(tmp_path_factory, name):
    root = tmp_path_factory.mktemp("n")
    fake_run(root, "fine")
    for fn in (data.resolve_run, data.safe_file):
        try:
            p = fn(root, name)
        except InputError as e:
            assert "\n" not in str(e)
            continue
        assert p.resolve().is_relative_to(root.resolve())


@settings(max_examples=60, deadline=None)
@given(st.dictionaries(st.sampled_from(["stats.csv", "log.txt", "config.toml", "run.lock"]),
                       st.binary(max_size=400), min_size=1))
def test_any_file_content_gives_a_row(tmp_path_factory, files):
    root = tmp_path_factory.mktemp("c")
    d = fake_run(root, "r")
    for name, raw in files.items():
        (d / name).write_bytes(raw)
    (row,) = data.list_runs(root)
    assert row.status in data.STATUSES
    json.dumps(row.row(), allow_nan=False)
    st_ = data.StatsTail(d / "stats.csv")
    st_.update()
    data.compare_runs([d])


def test_stats_tail_is_bounded(tmp_path):
    p = tmp_path / "stats.csv"
    with open(p, "wb") as fh:
        fh.write(b"generation,best_so_far\n")
        fh.write(b"0,1\n" * (768 << 10))  # 3 MiB
    t = data.StatsTail(p)
    t.CHUNK = 128 << 10
    t.MAX_BYTES = 1 << 20
    n = 0
    for _ in range(20):
        n += t.update()
    assert t.full and t.offset <= t.MAX_BYTES + t.CHUNK and n == len(t.rows) < 768 << 10
    p.write_bytes(b"x" * (256 << 10))  # cut back, one line longer than a chunk
    t.update()
    assert t.rows == [] and t.full


def test_readers_refuse_what_is_not_a_regular_file(tmp_path):
    os.mkfifo(tmp_path / "fifo")
    assert readers.read_range(tmp_path / "fifo", 0, 10) == (b"", 0)
    assert readers.read_range(Path("/dev/zero"), 0, 10) == (b"", 0)
    assert readers.head_tail(tmp_path / "fifo") == ("", "")
    for p in (tmp_path / "fifo", Path("/dev/zero"), tmp_path, tmp_path / "missing"):
        with pytest.raises(InputError):
            readers.regular_size(p, "file", 100)
    assert readers.check_robot("nao") == "nao" and readers.check_robot("") == ""
    for robot in ("/dev/zero", str(tmp_path / "fifo"), 5, "a\0b", str(tmp_path)):
        with pytest.raises(InputError, match="problem.robot"):
            readers.check_robot(robot)
