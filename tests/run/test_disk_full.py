"""A full or read-only disk: one line naming the path, never a traceback; once there is room,
``evomotion resume`` ends where an uninterrupted run ends (a real tmpfs; needs root)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from cluster_helpers import assert_same_run  # noqa: E402

ARGS = ["--set", "run.generations=300", "--set", "problem.dim=40", "--set",
        "algorithm.pop_size=64", "--set", "run.checkpoint_every=20", "-q"]


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "evomotion.cli", *args], capture_output=True,
                          text=True, timeout=300)


@pytest.fixture
def small_disk(tmp_path):
    disk = tmp_path / "disk"
    disk.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=160k", "tmpfs", str(disk)],
                       capture_output=True)
    if r.returncode != 0:
        pytest.skip("cannot mount a tmpfs here (needs root and CAP_SYS_ADMIN)")
    yield disk
    subprocess.run(["umount", "-l", str(disk)], check=False)


def _remount(disk: Path, opts: str) -> None:
    subprocess.run(["mount", "-o", f"remount,{opts}", str(disk)], check=True)


def test_disk_full_mid_run_then_resume(small_disk, tmp_path):
    ref = tmp_path / "ref"
    assert _cli("run", "functions", "--out", str(ref), *ARGS).returncode == 0
    out = small_disk / "run"
    r = _cli("run", "functions", "--out", str(out), *ARGS)
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert "no space left on the device" in r.stderr and str(out) in r.stderr
    assert not [p for p in out.rglob("*.tmp")]  # no partial file survives
    _remount(small_disk, "size=32m")
    r = _cli("resume", str(out), "-q")
    assert r.returncode == 0, r.stderr
    assert_same_run(ref, out)
    assert json.loads((out / "best.json").read_text())["generation"] == 300


def test_read_only_run_folder(small_disk, tmp_path):
    _remount(small_disk, "size=32m")
    out = small_disk / "run"
    assert _cli("run", "functions", "--out", str(out), "--set", "run.generations=3",
                "-q").returncode == 0
    _remount(small_disk, "ro")
    for args in (["resume", str(out), "--set", "run.generations=6", "-q"],
                 ["run", "functions", "--out", str(out), "--overwrite", "-q"],
                 ["plot", str(out)]):
        r = _cli(*args)
        assert r.returncode == 2 and "Traceback" not in r.stderr, (args, r.stderr)
        assert "read-only file system" in r.stderr, (args, r.stderr)
