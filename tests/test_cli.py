"""CLI behaviour: one-line errors for bad input, the README's commands, plot, resume."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from fixture_files import WEBOTS_MOTIONS

ROOT = Path(__file__).resolve().parents[1]


def cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "evomotion.cli", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=300)


@pytest.mark.parametrize("args,msg", [
    (["run", "nope"], "unknown study 'nope'; available: "),
    (["run", "functions", "--set", "algorithm.pop_size=-4"], "pop_size must be >= 2"),
    (["run", "functions", "--set", "algorithm.crossover=blx"], "unknown crossover 'blx'"),
    (["run", "functions", "--set", "run.bogus=1"], "unknown key 'run.bogus'"),
    (["resume", "/nonexistent/run"], "not a run folder"),
    (["run", "functions", "--evaluator", "mpi"], "unknown evaluator 'mpi'; available: "),
    (["run", "grid-path", "--evaluator", "mpi"], "unknown evaluator 'mpi'"),
])
def test_bad_input_is_one_line_error(tmp_path, args, msg):
    r = cli(*args, cwd=tmp_path)
    assert r.returncode == 2
    assert "Traceback" not in r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and msg in lines[0], r.stderr
    assert not (tmp_path / "runs").exists()  # nothing created for a rejected command


@pytest.mark.parametrize("args, msg", [
    (["replay", "--nope", "x.motion"], "error: No such option: --nope (see 'evomotion replay "
                                       "--help')"),
    (["replay"], "error: Missing argument 'motion'."),
    (["nosuch"], "error: No such command 'nosuch'."),
    (["plot", "r", "--out"], "error: Option '--out' requires an argument."),
])
def test_a_bad_option_or_argument_is_one_line(tmp_path, args, msg):
    """What the command-line parser itself refuses (an unknown option, a missing argument, a
    value of the wrong type) is one line too, not a usage block and a box."""
    r = cli(*args, cwd=tmp_path)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith(msg), r.stderr


def test_no_command_prints_the_help(tmp_path):
    r = cli(cwd=tmp_path)
    assert r.returncode == 2 and "Usage: evomotion" in r.stdout and "studies" in r.stdout


def test_malformed_toml(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[run]\nseed = \n")
    r = cli("run", "functions", "--config", str(bad), cwd=tmp_path)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert re.search(r"bad.toml:2: .*invalid TOML", r.stderr)


def test_run_resume_plot_studies(tmp_path):
    r = cli("run", "functions", "--set", "run.generations=12", "--set", "problem.dim=5",
            "--out", str(tmp_path / "r"), "--quiet")
    assert r.returncode == 0, r.stderr
    assert r.stdout == "" and r.stderr == ""  # --quiet and not a terminal: silent
    best = json.loads((tmp_path / "r" / "best.json").read_text())
    assert best["stop_reason"] == "generations" and best["generation"] == 12
    r = cli("plot", str(tmp_path / "r"), str(tmp_path / "r"), "--out", str(tmp_path / "cmp"))
    assert r.returncode == 0 and (tmp_path / "cmp.png").exists() and (tmp_path / "cmp.svg").exists()
    r = cli("studies")
    assert r.returncode == 0 and "functions" in r.stdout
    assert "--robot dm-humanoid: defaults of its own (run.generations, problem.sway_m" in r.stdout
    # gym's are per environment: the default one marked, another not, the method named
    out = r.stdout.splitlines()
    assert any("--set problem.env=Hopper-v5: defaults of its own (algorithm.name=cmaes" in x
               and "(also without --set problem.env)" in x for x in out)
    assert any("--set problem.env=Swimmer-v5: defaults" in x and "also without" not in x
               for x in out)
    assert any("(default cmaes; ars where problem.env has no defaults below)" in x for x in out)
    # --preset paper's own setting per task: listed where it differs from the preset's own
    paper = [x.strip() for x in out if x.strip().startswith("with --set problem.env=")]
    assert any(x.startswith("with --set problem.env=Swimmer-v5: its own") and
               "problem.normalize" in x for x in paper)
    assert not any("Hopper-v5" in x for x in paper)  # the preset's own setting: not repeated


def test_readme_commands_are_the_ci_commands():
    readme = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```sh\n(.*?)```", readme, re.S)
    assert len(blocks) >= 2
    main_job, tests = blocks[0].strip(), blocks[1].strip()
    assert "evomotion run" in main_job
    ci = (ROOT / ".ci" / "run").read_text()
    assert tests in ci


def test_readme_examples_run(tmp_path):
    readme = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```sh\n(.*?)```", readme, re.S)
    examples = [ln for ln in blocks[2].splitlines() if ln.startswith("evomotion ")]
    assert len(examples) >= 5
    for line in examples:
        args = line.split()[1:]
        r = cli(*args, "--quiet", cwd=tmp_path) if args[0] in ("run", "resume") else \
            cli(*args, cwd=tmp_path)
        assert r.returncode == 0, (line, r.stderr)
    assert (tmp_path / "runs" / "comparison.png").exists()
    stats = (tmp_path / "runs" / "mine" / "stats.csv").read_text().splitlines()
    assert stats[-1].startswith("100,")


def test_replay_json_only_on_stdout():
    motion = WEBOTS_MOTIONS / "HandWave.motion"
    r = cli("replay", str(motion), "--json")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert set(out) == {"displacement_m", "heading_change_rad", "fell", "fall_time_s"}
    assert out["fell"] is False


def test_replay_missing_file_is_one_line_error(tmp_path):
    r = cli("replay", str(tmp_path / "none.motion"))
    assert r.returncode == 2 and "Traceback" not in r.stderr and "no such motion" in r.stderr


def test_old_preset_name_runs_the_paper_preset_and_old_folders_resume(tmp_path):
    """``--preset seed`` is the old name of ``--preset paper`` (issue 32): it still runs, with
    one note line; a run folder that recorded the old name resumes."""
    out = tmp_path / "r"
    r = cli("run", "grid-path", "--preset", "seed", "--set", "run.generations=2",
            "--set", "algorithm.pop_size=16", "--set", "run.checkpoint_every=1",
            "--out", str(out), "--quiet")
    assert r.returncode == 0, r.stderr
    assert r.stderr.splitlines() == ["note: --preset seed is the old name of --preset paper"]
    toml = (out / "config.toml").read_text()
    assert 'preset = "paper"' in toml and 'update = "line_sweep"' in toml  # the paper's
    (out / "config.toml").write_text(toml.replace('preset = "paper"', 'preset = "seed"'))
    r = cli("resume", str(out), "--set", "run.generations=3", "--quiet")
    assert r.returncode == 0, r.stderr
    assert json.loads((out / "best.json").read_text())["generation"] == 3


def test_help_texts_keep_square_brackets():
    """Typer's rich help once ate ``[studio]`` as markup ("needs the  extra", issue 35): every
    command's help that names an extra shows it."""
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "studio", "--help"],
                       capture_output=True, text=True, timeout=60,
                       env={**__import__("os").environ, "COLUMNS": "200"})
    assert r.returncode == 0 and "needs the [studio] extra" in r.stdout, r.stdout
