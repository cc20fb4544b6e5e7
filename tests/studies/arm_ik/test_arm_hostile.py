"""arm-ik against hostile input (issue 31): ``study`` refuses non-physical numbers and bad
scenarios in one line before any run; ``board.png`` and ``best.gif`` are written through
the one atomic writer; the problem's floats have documented ranges."""

from __future__ import annotations

import os

import pytest
from hostile_cli import one_error, study_cli  # tests/studies/conftest.py

from evomotion.errors import InputError
from evomotion.studies.arm_ik.problem import ArmIKConfig

cli = study_cli("arm-ik")


@pytest.fixture()
def no_runs(monkeypatch):
    from evomotion.studies.arm_ik import experiment

    def evolve(*a, **k):
        raise AssertionError("a run started before the input was checked")

    monkeypatch.setattr(experiment, "evolve", evolve)


@pytest.mark.parametrize("args,needle", [
    (["--wall-seconds", "nan"], "--wall-seconds"),
    (["--wall-seconds", "1e300"], "--wall-seconds"),
    (["--seeds", str(10**9)], "--seeds"),
    (["--matching", "nearest"], "--matching"),
    (["--scenario", "three_fingers", "--scenario", "no_such_scenario"], "no_such_scenario"),
])
def test_study_refuses_bad_input_before_any_run(no_runs, args, needle):
    one_error(*cli("study", *args), needle)


def test_study_refuses_a_fifo_scenario_without_blocking(tmp_path, no_runs):
    fifo = tmp_path / "s.scen"
    os.mkfifo(fifo)
    one_error(*cli("study", "--scenario", str(fifo)), "FIFO")


def test_pictures_go_through_the_atomic_writer(tmp_path):
    from evomotion import outfile
    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study
    from evomotion.studies.arm_ik.study import STUDY

    seen: list[str] = []

    def hook(event, path):
        if event == "written":
            seen.append(path.name)

    cfg = resolve_config(STUDY, None, ["run.seed=1", "problem.gif_frames=3",
                                       "problem.scenario='three_fingers'", "run.videos=false"])
    outfile.WRITE_HOOKS.append(hook)
    try:
        run_study(STUDY, cfg, tmp_path / "run", quiet=True)
    finally:
        outfile.WRITE_HOOKS.remove(hook)
    assert {"board.png", "best.gif"} <= set(seen)
    assert not [p for p in (tmp_path / "run").iterdir() if p.name.endswith(".tmp.gif")]


@pytest.mark.parametrize("key,value", [("cell_size", 1e300), ("cell_size", float("nan")),
                                       ("tolerance", 2.0)])
def test_config_floats_have_a_documented_range(key, value):
    with pytest.raises(InputError, match=f"problem.{key}: expected"):
        ArmIKConfig(**{key: value}).validate()
