"""The run page's files, stderr, progress and metrics helpers (issue 35), without a browser."""

from __future__ import annotations

import os

import pytest

from evomotion.studio import run_files as rf
from evomotion.studio.run_tabs import metric_columns, smooth


def test_files_by_kind_without_links_checkpoints_or_hidden_files(tmp_path):
    run = tmp_path / "run"
    (run / "plots").mkdir(parents=True)
    (run / "checkpoints").mkdir()
    (run / "naoqi").mkdir()
    for rel in ("best.mp4", "plots/fitness.png", "best.motion", "policy.onnx", "naoqi/run.py",
                "config.toml", "log.txt", "weird.xyz", "checkpoints/gen-1.npz", ".secret"):
        (run / rel).write_bytes(b"x" * 10)
    os.symlink("/etc/passwd", run / "passwd.txt")
    files = rf.run_files(run)
    assert [(f.rel, f.kind) for f in files] == [
        ("best.mp4", "video"), ("plots/fitness.png", "image"), ("best.motion", "motion"),
        ("policy.onnx", "policy"), ("naoqi/run.py", "script"), ("config.toml", "data"),
        ("log.txt", "text"), ("weird.xyz", "other")]
    assert len(rf.run_files(run, limit=3)) == 3


def test_sizes_and_stderr_tail(tmp_path):
    assert rf.size_text(5) == "5 B" and rf.size_text(5300) == "5.2 kB"
    assert rf.stderr_tail(tmp_path) == ("", [])
    (tmp_path / "studio-stderr.txt").write_text("".join(f"line {i}\n" for i in range(100)))
    name, lines = rf.stderr_tail(tmp_path, 3)
    assert name == "studio-stderr.txt" and lines == ["line 97", "line 98", "line 99"]


def test_progress_gives_the_time_left_from_the_nearest_limit_while_running():
    cfg = {"run": {"generations": 100, "max_evaluations": 0, "wall_seconds": 0.0}}
    # 10 s for generations 0..9: 1 s per generation; generations 10..100 to go
    text = rf.progress(cfg, 9, 1000, 10.0, 100.0, True)
    assert text == ("generation 9 of 100, 1,000 evaluations, 100 evaluations/s, "
                    "about 1 min 31 s left")
    cfg["run"]["wall_seconds"] = 30.0  # the wall limit comes first: 20 s
    assert rf.progress(cfg, 9, 1000, 10.0, 100.0, True).endswith("about 20 s left")
    assert "left" not in rf.progress(cfg, 9, 1000, 10.0, 100.0, False)
    assert rf.progress({}, None, None, None, None, True) == "generation -, 0 evaluations"


def test_smoothing_is_a_debiased_moving_average_that_skips_gaps():
    assert smooth([1.0, None, 3.0], 0.0) == [1.0, None, 3.0]
    out = smooth([2.0, None, 2.0, 2.0], 0.9)
    assert out[1] is None and out[0] == pytest.approx(2.0) and out[3] == pytest.approx(2.0)
    assert smooth([0.0, 10.0], 0.5)[1] == pytest.approx(10.0 * 0.5 / 0.75)
    assert metric_columns(["generation", "evaluations", "best"]) == ["evaluations", "best"]


def test_decimation_keeps_the_envelope_the_ends_and_the_gaps():
    from evomotion.studio.run_tabs import decimate

    x = list(range(10000))
    y = [float(i % 7) for i in x]
    y[5000] = 100.0  # a spike
    y[7000] = None
    out = decimate(x, y, 2000)
    assert len(out) <= 2002 and out[0] == [0, 0.0] and out[-1][0] == 9999
    assert [5000, 100.0] in out and max(p[1] for p in out if p[1] is not None) == 100.0
    assert min(p[1] for p in out if p[1] is not None) == 0.0
    assert decimate([0, 1], [None, 2.0]) == [[0, None], [1, 2.0]]
