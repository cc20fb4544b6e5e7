"""Naming a new run and extending a finished one (issue 35), without a browser."""

from __future__ import annotations

import pytest

from evomotion.errors import InputError
from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.studies import get_study
from evomotion.studio import actions


@pytest.mark.parametrize("name", ["", "../x", "a b", ".hidden", "x/y", "é", "a" * 81, "-x"])
def test_bad_run_names_are_one_line(tmp_path, name):
    with pytest.raises(InputError) as e:
        actions.check_run_name(tmp_path, name)
    assert "\n" not in str(e.value) and "run name" in str(e.value)


def test_a_taken_name_is_refused_and_a_free_one_is_made(tmp_path):
    (tmp_path / "taken").mkdir()
    with pytest.raises(InputError, match="exists already"):
        actions.make_run_folder(tmp_path, "functions", "taken")
    out = actions.make_run_folder(tmp_path, "functions", "mine-1.b")
    assert out == tmp_path / "mine-1.b" and (out / ".evomotion-run").exists()


def test_extend_needs_a_finished_run_and_more_generations(tmp_path):
    s = get_study("functions")
    run_study(s, resolve_config(s, None, ["run.generations=3"]), tmp_path / "fn", quiet=True)
    for bad in (3, 2, -1, 2.5, True):
        with pytest.raises(InputError, match="above the run's 3"):
            actions.extend_run(tmp_path, "fn", bad)
    (tmp_path / "empty").mkdir()
    (tmp_path / "empty" / "config.toml").write_text('study = "functions"\n')
    with pytest.raises(InputError):
        actions.extend_run(tmp_path, "empty", 10)
    proc = actions.extend_run(tmp_path, "fn", 5)
    assert proc.wait(60) == 0
    assert "generation 5" in (tmp_path / "fn" / "log.txt").read_text().splitlines()[-1]
