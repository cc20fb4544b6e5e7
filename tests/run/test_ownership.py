"""A run folder is what a run marked as its own; --overwrite removes only what runs wrote
(it deleted a whole project folder that merely held a config.toml)."""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from evomotion.outfile import RUN_MARKER, read_marker

ARGS = ["--set", "run.generations=3", "--set", "problem.dim=3", "--set",
        "algorithm.pop_size=8", "-q"]


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "evomotion.cli", *args], capture_output=True,
                          text=True, timeout=120)


def _tree(d: Path) -> dict[str, str]:
    """Every entry under ``d`` with a digest of its contents (links as their target)."""
    out = {}
    for root, dirs, files in os.walk(d):
        for name in dirs + files:
            p = Path(root) / name
            rel = str(p.relative_to(d))
            if p.is_symlink():
                out[rel] = "-> " + os.readlink(p)
            elif p.is_file():
                out[rel] = hashlib.sha256(p.read_bytes()).hexdigest()
            else:
                out[rel] = "dir"
    return out


def _project(d: Path) -> Path:
    d.mkdir()
    (d / "config.toml").write_text("[run]\nseed = 1\n")
    (d / "thesis.tex").write_text("\\documentclass{article}\n")
    (d / "src").mkdir()
    (d / "src" / "main.py").write_text("print(1)\n")
    (d / ".git").mkdir()
    (d / ".git" / "HEAD").write_text("ref: refs/heads/main\n")
    return d


@pytest.mark.parametrize("overwrite", [True, False])
def test_project_folder_with_a_config_is_never_emptied(tmp_path, overwrite):
    d = _project(tmp_path / "project")
    before = _tree(d)
    r = _cli("run", "functions", "--out", str(d), *ARGS, *(["--overwrite"] if overwrite else []))
    assert r.returncode == 2 and "Traceback" not in r.stderr
    line = r.stderr.strip()
    assert "\n" not in line and "files no run wrote" in line
    assert ".git" in line and "thesis.tex" in line and "nothing was deleted" in line
    assert _tree(d) == before  # not even a run.lock


def test_overwrite_of_a_run_folder(tmp_path):
    d = tmp_path / "run"
    assert _cli("run", "functions", "--out", str(d), *ARGS).returncode == 0
    doc = read_marker(d)
    assert doc["study"] == "functions"
    assert {"config.toml", "stats.csv", "plots", "best.json", "log.txt"} <= set(doc["files"])
    r = _cli("run", "functions", "--out", str(d), *ARGS)
    assert r.returncode == 2 and "already holds a run" in r.stderr
    best = (d / "best.json").read_text()
    assert _cli("run", "functions", "--out", str(d), *ARGS, "--overwrite").returncode == 0
    assert (d / "best.json").read_text() == best


def test_overwrite_refuses_a_run_folder_holding_a_users_file(tmp_path):
    d = tmp_path / "run"
    assert _cli("run", "functions", "--out", str(d), *ARGS).returncode == 0
    (d / "notes.md").write_text("my notes\n")
    (d / "plots" / "mine.png").write_bytes(b"x")  # inside a run's folder: the run's to remove
    before = _tree(d)
    r = _cli("run", "functions", "--out", str(d), *ARGS, "--overwrite")
    assert r.returncode == 2 and "notes.md" in r.stderr and "nothing was deleted" in r.stderr
    assert _tree(d) == before


def test_overwrite_removes_a_link_not_what_it_points_at(tmp_path):
    d = tmp_path / "run"
    assert _cli("run", "functions", "--out", str(d), *ARGS).returncode == 0
    outside = tmp_path / "precious"
    outside.mkdir()
    (outside / "data.txt").write_text("keep\n")
    shutil.rmtree(d / "plots")
    (d / "plots").symlink_to(outside, target_is_directory=True)
    assert _cli("run", "functions", "--out", str(d), *ARGS, "--overwrite").returncode == 0
    assert (outside / "data.txt").read_text() == "keep\n"
    assert (d / "plots").is_dir() and not (d / "plots").is_symlink()


def test_unmarked_old_run_folder_resumes_but_is_not_overwritten(tmp_path):
    d = tmp_path / "run"
    assert _cli("run", "functions", "--out", str(d), *ARGS).returncode == 0
    (d / RUN_MARKER).unlink()  # a folder written before runs marked their folders
    before = _tree(d)
    r = _cli("run", "functions", "--out", str(d), *ARGS, "--overwrite")
    assert r.returncode == 2 and "written before run folders were marked" in r.stderr
    assert _tree(d) == before
    r = _cli("resume", str(d), "--set", "run.generations=5", "-q")
    assert r.returncode == 0, r.stderr


def test_new_run_into_an_empty_existing_folder(tmp_path):
    d = tmp_path / "empty"
    d.mkdir()
    assert _cli("run", "functions", "--out", str(d), *ARGS).returncode == 0
    assert (d / RUN_MARKER).is_file()


def test_experiment_output_folders_are_owned_too(tmp_path):
    """`humanoid-step study --out project` wrote its curves into a project folder."""
    from evomotion.errors import InputError
    from evomotion.outfile import atomic_write_text
    from evomotion.run.folder import make_output_folder

    d = _project(tmp_path / "project")
    before = _tree(d)
    with pytest.raises(InputError, match="files this program did not write"):
        make_output_folder("humanoid-step-study", d)
    assert _tree(d) == before
    with pytest.raises(InputError, match="does not exist"):
        make_output_folder("x", tmp_path / "no" / "such")
    assert not (tmp_path / "no").exists()
    out = make_output_folder("x", tmp_path / "results")
    atomic_write_text(out / "table.md", "| a |\n")
    assert make_output_folder("x", out) == out  # its own earlier outputs: replaced later
    (out / "mine.txt").write_text("user\n")
    with pytest.raises(InputError, match="mine.txt"):
        make_output_folder("x", out)


def test_plot_out_into_a_missing_folder_makes_nothing(tmp_path):
    d = tmp_path / "run"
    assert _cli("run", "functions", "--out", str(d), *ARGS).returncode == 0
    r = _cli("plot", str(d), "--out", str(tmp_path / "missing" / "fig"))
    assert r.returncode == 2 and "does not exist" in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "missing").exists()


def test_a_config_the_problem_refuses_makes_no_folder_and_keeps_an_old_run(tmp_path):
    """A stance beyond a joint's range is refused when the problem is built: that left an empty
    folder with a marker and a lock behind, and --overwrite had already emptied the old run."""
    bad = ("--set", "problem.stance_width_rad=0.9", "--set", "problem.threads=1", "-q")
    r = _cli("run", "humanoid-balance", "--out", str(tmp_path / "new"), *bad)
    assert r.returncode == 2 and "LHipRoll" in r.stderr and "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "new").exists()
    empty = tmp_path / "empty"
    empty.mkdir()
    assert _cli("run", "humanoid-balance", "--out", str(empty), *bad).returncode == 2
    assert empty.is_dir() and not any(empty.iterdir())  # the user's folder: left as it was
    old = tmp_path / "old"
    assert _cli("run", "functions", "--out", str(old), *ARGS).returncode == 0
    before = _tree(old)
    r = _cli("run", "humanoid-balance", "--out", str(old), "--overwrite", *bad)
    assert r.returncode == 2 and "LHipRoll" in r.stderr
    assert _tree(old) == before
    # the missing parents --out made go too, and an optimizer's refusal is one line as well
    r = _cli("run", "humanoid-balance", "--out", str(tmp_path / "a" / "b" / "c"), *bad)
    assert r.returncode == 2 and not (tmp_path / "a").exists()
    r = _cli("run", "functions", "--out", str(tmp_path / "d" / "e"), *ARGS, "--set",
             "algorithm.name=snes", "--set", "algorithm.noise_table=1")
    assert r.returncode == 2 and "algorithm.noise_table" in r.stderr
    assert "Traceback" not in r.stderr and not (tmp_path / "d").exists()
    # without --out: the named folder under an existing runs/ goes, runs/ stays
    (tmp_path / "w" / "runs").mkdir(parents=True)
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "humanoid-balance",
                        *bad], capture_output=True, text=True, timeout=120, cwd=tmp_path / "w")
    assert r.returncode == 2 and "LHipRoll" in r.stderr
    assert (tmp_path / "w" / "runs").is_dir() and not any((tmp_path / "w" / "runs").iterdir())


def test_a_missing_logger_package_refuses_before_overwrite_empties_the_old_run(tmp_path):
    """--overwrite emptied the old run and only then loaded the loggers: a missing
    tensorboardX refused the run after the old one was gone. A stand-in module that cannot be
    imported plays the missing package."""
    old = tmp_path / "old"
    assert _cli("run", "functions", "--out", str(old), *ARGS).returncode == 0
    before = _tree(old)
    fake = tmp_path / "site"
    fake.mkdir()
    (fake / "tensorboardX.py").write_text(
        "raise ModuleNotFoundError(\"No module named 'tensorboardX'\", name='tensorboardX')\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(fake), *filter(None, [os.environ.get("PYTHONPATH")])])}
    for out, more in ((old, ["--overwrite"]), (tmp_path / "new" / "run", [])):
        r = subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "functions", "--out",
                            str(out), *more, *ARGS, "--set", 'run.loggers=["tensorboard"]'],
                           capture_output=True, text=True, timeout=120, env=env)
        assert r.returncode == 2 and "tensorboardX" in r.stderr, r.stderr
        assert "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert _tree(old) == before
    assert not (tmp_path / "new").exists()


def test_a_run_the_lock_refuses_closes_the_driver_it_built(tmp_path, monkeypatch):
    from evomotion.run import runner
    from evomotion.run.config import resolve_config
    from evomotion.studies import get_study

    s = get_study("functions")
    cfg = resolve_config(s, None, ["run.generations=2", "problem.dim=3",
                                   "algorithm.pop_size=8"])
    closed = []
    real = runner._prepare

    def prepare(*a):
        config, problem, driver = real(*a)
        monkeypatch.setattr(driver, "close", lambda: closed.append(True))
        return config, problem, driver

    class RefusedError(RuntimeError):
        pass

    def refuse(_out):
        raise RefusedError("held by another run")

    monkeypatch.setattr(runner, "_prepare", prepare)
    monkeypatch.setattr(runner, "RunLock", refuse)
    with pytest.raises(RefusedError):
        runner.run_study(s, cfg, tmp_path / "run", quiet=True)
    assert closed == [True]
