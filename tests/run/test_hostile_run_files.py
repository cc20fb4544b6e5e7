"""Damaged or hostile files in a run folder (issue 31): one line or a fallback, never a
traceback, a huge allocation, a zero-padded file or a forged log line."""

from __future__ import annotations

import contextlib
import io
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.errors import InputError
from evomotion.npzio import loads_npz

ARGS = ["-q", "--set", "problem.dim=4", "--set", "algorithm.pop_size=20",
        "--set", "run.checkpoint_every=4"]


def _cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "evomotion.cli", *args], capture_output=True,
                          text=True, timeout=120, cwd=cwd)


def _one_line(r: subprocess.CompletedProcess) -> str:
    assert r.returncode != 0 and "Traceback" not in r.stderr, r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("error:")]
    assert len(lines) == 1, r.stderr
    return lines[0]


@pytest.fixture(scope="module")
def run10(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("r") / "run"
    assert _cli("run", "functions", "--out", str(out), "--set", "run.generations=10",
                "--set", "run.history_every=1", *ARGS).returncode == 0
    return out


def _copy(src: Path, dst: Path) -> Path:
    import shutil

    shutil.copytree(src, dst)
    return dst


def _npy_header_claiming(shape: tuple[int, ...]) -> bytes:
    """A valid .npy member whose header declares ``shape`` but holds 8 bytes of data."""
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": "<f8", "fortran_order": False,
                                               "shape": shape})
    return buf.getvalue() + b"\0" * 8


def _huge_npz(path: Path) -> None:
    import zipfile

    with zipfile.ZipFile(path, "w") as z:
        z.writestr("state.pop.npy", _npy_header_claiming((10**7, 10**7)))


def test_huge_declared_shape_in_the_newest_checkpoint_falls_back(run10, tmp_path):
    d = _copy(run10, tmp_path / "run")
    ck = d / "checkpoints"
    latest = json.loads((ck / "latest.json").read_text())["checkpoint"]
    _huge_npz(ck / latest.replace(".json", ".npz"))
    r = _cli("resume", str(d), "--set", "run.generations=12", "-q")
    assert r.returncode == 0, r.stderr
    log = (d / "log.txt").read_text()
    assert "declares shape (10000000, 10000000)" in log and "resuming from the newest valid" \
        in log


def test_emptied_history_is_refused_not_padded(run10, tmp_path):
    """': > RUN/population.bin; resume' left it zero-padded and unreadable."""
    d = _copy(run10, tmp_path / "run")
    (d / "population.bin").write_bytes(b"")
    line = _one_line(_cli("resume", str(d), "--set", "run.generations=12", "-q"))
    assert "population.bin" in line and "past the end" in line
    assert (d / "population.bin").read_bytes() == b""


def test_deeply_nested_checkpoint_json_falls_back(run10, tmp_path):
    d = _copy(run10, tmp_path / "run")
    ck = d / "checkpoints"
    latest = json.loads((ck / "latest.json").read_text())["checkpoint"]
    (ck / latest).write_text("[" * 100000 + "]" * 100000)
    r = _cli("resume", str(d), "--set", "run.generations=12", "-q")
    assert r.returncode == 0, r.stderr
    assert "nested at most" in (d / "log.txt").read_text()


def test_newlines_in_names_cannot_forge_log_lines(tmp_path):
    out = tmp_path / "a\nstopped: done at generation 99"
    r = _cli("run", "functions", "--out", str(out), "--set", "run.generations=2", *ARGS)
    assert r.returncode == 0, r.stderr
    lines = (out / "log.txt").read_text().splitlines()
    assert [ln for ln in lines if ln.startswith("stopped:")] == \
        ["stopped: generations at generation 2 after 60 evaluations"]
    assert "a\\nstopped: done" in lines[0]


@pytest.mark.parametrize("damage", ["no header", "header only", "binary", "shuffled columns",
                                    "generation column text", "fifo"])
def test_plot_on_a_damaged_stats_file(run10, tmp_path, damage):
    d = _copy(run10, tmp_path / "run")
    p = d / "stats.csv"
    rows = p.read_text().splitlines()
    if damage == "no header":
        p.write_text("\n".join(rows[1:]) + "\n")
    elif damage == "header only":
        p.write_text("generation,evaluations\n")
    elif damage == "binary":
        p.write_bytes(os.urandom(4000))
    elif damage == "shuffled columns":
        p.write_text("\n".join([rows[0]] + rows[:0:-1]) + "\n")
    elif damage == "generation column text":
        p.write_text(rows[0].replace("generation", "gen") + "\n" + "\n".join(rows[1:]) + "\n")
    else:
        p.unlink()
        os.mkfifo(p)
    r = _cli("plot", str(d))
    line = _one_line(r)
    assert "stats" in line


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=600))
def test_npz_reader_fuzz(data):
    with contextlib.suppress(InputError):
        loads_npz(data, "x.npz")


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(min_value=0, max_value=2**62), min_size=1, max_size=4))
def test_npz_declared_shapes_are_checked_before_allocation(shape):
    import zipfile

    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        z.writestr("a.npy", _npy_header_claiming(tuple(shape)))
    n = int(np.prod(np.array(shape, dtype=object)))
    if n * 8 <= 8:  # fits its 8 bytes (numpy may still refuse a shape like (0, 2**30, 2**30))
        with contextlib.suppress(InputError):
            assert loads_npz(buf.getvalue(), "x.npz")["a"].size == n
    else:
        with pytest.raises(InputError, match="declares shape"):
            loads_npz(buf.getvalue(), "x.npz")


def test_json_depth_is_linear_in_the_text():
    """An unterminated-string pattern made the scan quadratic: 80 KB of \\" took 20 s."""
    import time

    from evomotion.textio import json_depth

    t0 = time.perf_counter()
    assert json_depth('\\"' * 500_000, 32) == 0
    assert time.perf_counter() - t0 < 2.0


def test_zero_size_dtypes_cannot_declare_huge_shapes():
    import zipfile

    for descr in ("|S0", "|V0"):
        buf, member = io.BytesIO(), io.BytesIO()
        np.lib.format.write_array_header_1_0(member, {"descr": descr, "fortran_order": False,
                                                      "shape": (2**40,)})
        with zipfile.ZipFile(buf, "w") as z:
            z.writestr("a.npy", member.getvalue())
        with pytest.raises(InputError):
            loads_npz(buf.getvalue(), "x.npz")


def test_resume_of_a_folder_that_is_no_run_touches_nothing(tmp_path):
    d = tmp_path / "proj"
    (d / "checkpoints").mkdir(parents=True)
    (d / "config.toml").write_text('study = "functions"\n')
    (d / ".draft.tmp").write_text("mine\n")
    before = sorted(p.name for p in d.iterdir())
    line = _one_line(_cli("resume", str(d)))
    assert "no checkpoint to resume from" in line
    assert sorted(p.name for p in d.iterdir()) == before  # no run.lock, log.txt, stats.csv
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("x\n")
    assert "not a run folder" in _one_line(_cli("resume", str(other)))
    assert sorted(p.name for p in other.iterdir()) == ["notes.txt"]


def test_a_stagnated_run_killed_while_finishing_only_finishes(tmp_path):
    """finish_only needed a limit or the method's own stop: stagnation ran on."""
    d = tmp_path / "run"
    args = ("run", "functions", "--out", str(d), "--set", "run.generations=200",
            "--set", "run.stagnation_generations=2", "--set", "run.stagnation_eps=1e9", *ARGS)
    assert _cli(*args).returncode == 0
    ck = d / "checkpoints"
    latest = json.loads((ck / "latest.json").read_text())["checkpoint"]
    meta = json.loads((ck / latest).read_text())
    assert meta["counters"]["stop_reason"] == "stagnation"
    meta["counters"]["finished"] = False
    (ck / latest).write_text(json.dumps(meta))
    rows = (d / "stats.csv").read_text()
    (d / "best.json").unlink()
    assert _cli("resume", str(d), "-q").returncode == 0
    assert (d / "stats.csv").read_text() == rows and (d / "best.json").is_file()
    assert "to write the final artifacts" in (d / "log.txt").read_text()


@pytest.mark.parametrize("shape", [(2,), (1, 2), (3,)])
def test_a_member_a_few_elements_short_is_refused_by_its_header(shape):
    """The header's own bytes once counted as array data: (2,) of float64 (16 bytes) in a
    member holding 8 passed the header check and failed later as an EOF."""
    import zipfile

    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        z.writestr("a.npy", _npy_header_claiming(shape))
    with pytest.raises(InputError, match="declares shape .* but holds 8 bytes"):
        loads_npz(buf.getvalue(), "x.npz")
