"""Issue 34: ``humanoid-walk`` is the closed-loop walk controller (once ``humanoid-omniwalk``)
and its ``--preset open-loop`` the open-loop walk (the study ``humanoid-walk-open-loop``,
once ``humanoid-walk``); commands and run folders with the old names keep working, resumed
bit for bit."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from evomotion import api
from evomotion.cli import app
from evomotion.errors import InputError
from evomotion.run.config import config_from_run_dir, current_study_name, resolve_config
from evomotion.run.stats import read_stats
from evomotion.studies import get_study, study_with_preset

OPEN_LOOP_TINY = ("algorithm.pop_size=4", "problem.walk_s=0.5", "problem.hold_s=0.2",
                  "problem.worlds=2", "run.videos=false", "run.checkpoint_every=1")
CLOSED_LOOP_TINY = ("problem.duration_s=0.5", "problem.eval_episodes=1", "problem.episodes=1",
                    "problem.threads=1", "algorithm.pop_size=4", "algorithm.top_directions=0",
                    "run.videos=false", "run.checkpoint_every=1")


def test_the_walk_default_is_the_controller_and_open_loop_its_preset():
    walk = get_study("humanoid-walk")
    assert walk.name == "humanoid-walk" and walk.problem_config.__name__ == "OmniWalkConfig"
    assert get_study("humanoid-omniwalk") is walk  # the old name
    s, preset = study_with_preset("humanoid-walk", "open-loop")
    assert (s.name, preset) == ("humanoid-walk-open-loop", None)
    assert s.problem_config.__name__ == "HumanoidWalkConfig"
    assert study_with_preset("humanoid-walk-open-loop", "nominal")[1] == "nominal"
    with pytest.raises(InputError, match="available: open-loop"):
        resolve_config(walk, None, (), preset="paper")


def test_studies_lists_the_preset_and_old_names_mount_their_commands():
    out = CliRunner().invoke(app, ["studies"]).output
    block = out[out.index("humanoid-walk "):out.index("humanoid-walk-open-loop")]
    assert "--preset open-loop" in block
    proc = subprocess.run([sys.executable, "-m", "evomotion.cli", "humanoid-omniwalk", "compare",
                           "--help"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and "walk engine" in proc.stdout


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "evomotion.cli", *args], capture_output=True,
                          text=True, timeout=600)


def _sets(items) -> list[str]:
    return [a for s in items for a in ("--set", s)]


def _as_old(run: Path, old: str) -> None:
    """Make ``run`` look written before the rename: its config and checkpoints name ``old``."""
    cfg = run / "config.toml"
    cfg.write_text(re.sub(r'^study = ".*"$', f'study = "{old}"', cfg.read_text(), count=1,
                          flags=re.M))
    for ck in (run / "checkpoints").glob("gen-*.json"):
        meta = json.loads(ck.read_text())
        meta["config"]["study"] = old
        ck.write_text(json.dumps(meta))


@pytest.mark.parametrize("args,tiny,old", [
    (("humanoid-walk", "--preset", "open-loop"), OPEN_LOOP_TINY, "humanoid-walk"),
    (("humanoid-walk",), CLOSED_LOOP_TINY, "humanoid-omniwalk"),
])
def test_a_run_folder_of_the_old_name_resumes_bit_for_bit(tmp_path, args, tiny, old):
    """A run of 2 generations, renamed back to its old study name (config.toml and the
    checkpoints' records), resumed to 3 generations: the same stats as a run of 3."""
    full, part = tmp_path / "full", tmp_path / "part"
    for out, gens in ((full, 3), (part, 2)):
        proc = _cli("run", *args, *_sets(tiny), "--set", f"run.generations={gens}",
                    "--out", str(out), "--quiet")
        assert proc.returncode == 0, proc.stderr
    new = config_from_run_dir(full)[0]
    assert new == ("humanoid-walk-open-loop" if "open-loop" in args else "humanoid-walk")
    _as_old(part, old)
    assert config_from_run_dir(part)[0] == new  # read under the name now
    proc = _cli("resume", str(part), "--set", "run.generations=3", "--quiet")
    assert proc.returncode == 0, proc.stderr
    a, b = read_stats(full / "stats.csv"), read_stats(part / "stats.csv")
    assert set(a) == set(b) and len(a["generation"]) == 4
    for col in set(a) - {"wall_s", "evals_per_s"}:
        np.testing.assert_array_equal(a[col], b[col], err_msg=col)


def test_the_rename_rule_reads_the_problem_keys():
    assert current_study_name("humanoid-walk", {"walk_s": 10.0}) == "humanoid-walk-open-loop"
    assert current_study_name("humanoid-walk", {"duration_s": 8.0}) == "humanoid-walk"
    assert current_study_name("humanoid-omniwalk") == "humanoid-walk"
    assert current_study_name("gym", {"walk_s": 1}) == "gym"


def test_the_api_runs_the_preset_study(tmp_path):
    res = api.run("humanoid-walk", {"run": {"generations": 1}, "problem": {
        "walk_s": 0.5, "hold_s": 0.2, "worlds": 2}, "algorithm": {"pop_size": 4}},
        tmp_path / "run", preset="open-loop")
    assert res.exit_code == 0
    assert config_from_run_dir(tmp_path / "run")[0] == "humanoid-walk-open-loop"
    _as_old(tmp_path / "run", "humanoid-walk")  # the API resumes it by either name
    for name, gens in (("humanoid-walk", 2), ("humanoid-walk-open-loop", 3)):
        res = api.run(name, {"run": {"generations": gens}}, tmp_path / "run", resume=True)
        assert res.exit_code == 0 and res.generation == gens


def test_every_preset_study_is_registered_and_named_apart_from_the_presets():
    from evomotion.studies import all_studies

    for s in all_studies():
        for preset, target in s.preset_studies.items():
            assert preset not in s.presets and preset in s.preset_notes, (s.name, preset)
            assert get_study(target).name == target != s.name


def test_old_folders_are_named_as_now_everywhere_they_are_listed(tmp_path):
    """The studio's run list and compare table and ``evomotion.load_run`` name an old
    folder's study as it is now (a folder holding only its config is enough to be named)."""
    from evomotion.studio.compare import configs
    from evomotion.studio.data import study_name

    folders = {"open": ('study = "humanoid-walk"\n\n[problem]\nwalk_s = 10.0\n',
                        "humanoid-walk-open-loop"),
               "omni": ('study = "humanoid-omniwalk"\n\n[problem]\nduration_s = 8.0\n',
                        "humanoid-walk"),
               "now": ('study = "humanoid-walk"\n\n[problem]\nduration_s = 8.0\n',
                       "humanoid-walk")}
    for name, (text, want) in folders.items():
        (tmp_path / name).mkdir()
        (tmp_path / name / "config.toml").write_text(text)
        assert study_name(tmp_path / name) == want
        assert api.load_run(tmp_path / name).study == want
    assert [c["study"] for c in configs([tmp_path / n for n in folders])] == \
        [want for _, want in folders.values()]


def test_a_preset_of_the_preset_study_says_where_it_is():
    with pytest.raises(InputError, match="'nominal' is a preset of humanoid-walk-open-loop"):
        study_with_preset("humanoid-walk", "nominal")
