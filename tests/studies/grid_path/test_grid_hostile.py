"""grid-path against hostile input (issue 31): ``make-map`` and ``study`` refuse bad numbers,
rows and outputs in one line before any work; the map and ``path.png`` are written through
the one atomic writer; a random map is searched for a bounded time; the problem's floats
have documented ranges."""

from __future__ import annotations

import os

import numpy as np
import pytest
from hostile_cli import one_error, study_cli  # tests/studies/conftest.py

from evomotion.errors import InputError
from evomotion.studies.grid_path.problem import GridPathConfig

cli = study_cli("grid-path")


@pytest.fixture()
def no_work(monkeypatch):
    from evomotion.studies.grid_path import experiments, study

    def work(*a, **k):
        raise AssertionError("the work started before the input was checked")

    monkeypatch.setattr(experiments, "evolve", work)
    monkeypatch.setattr(study, "random_map", work)


@pytest.mark.parametrize("args,needle", [
    (["--size", str(10**6)], "--size"),
    (["--density", "nan"], "--density"),
    (["--density", "1"], "--density"),
    (["--seed", "-1"], "--seed"),
])
def test_make_map_refuses_bad_numbers(tmp_path, no_work, args, needle):
    one_error(*cli("make-map", tmp_path / "m.map", *args), needle)
    assert not (tmp_path / "m.map").exists()


def test_make_map_checks_its_output_before_drawing(tmp_path, no_work):
    one_error(*cli("make-map", tmp_path / "no" / "m.map"), "does not exist")
    dev = tmp_path / "dev.map"
    dev.symlink_to(os.devnull)
    one_error(*cli("make-map", dev), "device")
    fifo = tmp_path / "fifo.map"
    os.mkfifo(fifo)
    one_error(*cli("make-map", fifo), "FIFO")


def test_make_map_writes_atomically(tmp_path):
    from evomotion.studies.grid_path.maps import read_map

    out = tmp_path / "m.map"
    assert cli("make-map", out, "--size", "12")[0] == 0
    assert read_map(out).blocked.shape == (12, 12)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.map"]


@pytest.mark.parametrize("args,needle", [
    (["--row", "no-such-row"], "--row"),
    (["--experiment", "beyond", "--row", "cga-L5-line"], "--row"),
    (["--pc", "nan"], "--pc"),
    (["--pm", "2"], "--pm"),
    (["--n-maps", str(10**9)], "--n-maps"),
    (["--pop", str(10**9)], "--pop"),
    (["--generations", "-1"], "--generations"),
    (["--experiment", "other"], "--experiment"),
    (["--update", "sideways"], "--update"),
])
def test_study_refuses_bad_input_before_any_run(no_work, args, needle):
    one_error(*cli("study", "--seeds", "1", *args), needle)


def test_a_random_map_search_is_bounded():
    """No connected map at 90% density: refused after a few tries of a large map (it used
    to try 1000 times, about 15 minutes at 2048 x 2048)."""
    from evomotion.studies.grid_path.maps import random_map

    with pytest.raises(InputError, match="no connected"):
        random_map(2048, 0.9, np.random.default_rng(0))


def test_path_picture_goes_through_the_atomic_writer(tmp_path):
    from evomotion import outfile
    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study
    from evomotion.studies import get_study

    seen: list[str] = []

    def hook(event, path):
        if event == "written":
            seen.append(path.name)

    s = get_study("grid-path")
    cfg = resolve_config(s, None, [*s.smoke, "run.generations=2", "run.videos=false"])
    outfile.WRITE_HOOKS.append(hook)
    try:
        run_study(s, cfg, tmp_path / "run", quiet=True)
    finally:
        outfile.WRITE_HOOKS.remove(hook)
    assert "path.png" in seen


@pytest.mark.parametrize("key,value", [("m", 1e300), ("penalty", 1e300),
                                       ("repair_radius", 1e300), ("penalty", float("nan"))])
def test_config_floats_have_a_documented_range(key, value):
    with pytest.raises(InputError, match=f"problem.{key}: expected"):
        GridPathConfig(**{key: value}).validate()
