"""humanoid-step against hostile input (issue 31): ``study`` refuses non-physical numbers and
unwritable outputs in one line before any run (and makes no folder for a mistyped path);
the problem's floats have documented ranges."""

from __future__ import annotations

import pytest
from hostile_cli import one_error, study_cli  # tests/studies/conftest.py

from evomotion.errors import InputError
from evomotion.studies.humanoid_step.problem import HumanoidStepConfig

cli = study_cli("humanoid-step")


@pytest.fixture()
def no_runs(monkeypatch):
    from evomotion.studies.humanoid_step import experiment

    def run_one(*a, **k):
        raise AssertionError("a run started before the input was checked")

    monkeypatch.setattr(experiment, "run_one", run_one)


@pytest.mark.parametrize("args,needle", [
    (["--bounds-scale", "nan"], "--bounds-scale"),
    (["--bounds-scale", "2"], "--bounds-scale"),
    (["--intervals", "1"], "--intervals"),
    (["--pop", str(10**9)], "--pop"),
    (["--generations", str(10**9)], "--generations"),
    (["--seeds", "0"], "--seeds"),
    (["--workers", "-1"], "--workers"),
])
def test_study_refuses_non_physical_numbers_before_making_its_folder(tmp_path, no_runs, args,
                                                                      needle):
    one_error(*cli("study", "--out", tmp_path / "s", "--workers", "1", *args), needle)
    assert not (tmp_path / "s").exists()


def test_study_outputs_are_checked_before_any_run(tmp_path, no_runs):
    one_error(*cli("study", "--out", tmp_path / "no" / "such", "--workers", "1"),
              "does not exist")
    assert not (tmp_path / "no").exists()
    (tmp_path / "s" / "results.csv").mkdir(parents=True)
    one_error(*cli("study", "--out", tmp_path / "s", "--workers", "1"), "results.csv")


@pytest.mark.parametrize("key,value", [("motion_s", 1e300), ("distance_weight", 1e300),
                                       ("step_min_m", 1e300), ("forward_cap_m", 1e300),
                                       ("fall_height_m", 1e300), ("segment_s", 1e300),
                                       ("heading_tolerance_rad", 1e300), ("hold_s", -1.0)])
def test_config_floats_have_a_documented_range(key, value):
    with pytest.raises(InputError, match=f"problem.{key}: expected"):
        HumanoidStepConfig(**{key: value}).validate()
