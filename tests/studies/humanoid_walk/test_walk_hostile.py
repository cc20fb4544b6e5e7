"""humanoid-walk-open-loop against hostile input (issue 31): ``compare`` checks that a run
folder is a
humanoid-walk-open-loop run of the NAO (from its config.toml) before replaying anything, and the
problem's floats have documented ranges."""

from __future__ import annotations

from pathlib import Path

import pytest
from hostile_cli import one_error, study_cli  # tests/studies/conftest.py

from evomotion.errors import InputError
from evomotion.sim.motion import format_motion
from evomotion.sim.robots.nao.webots_motions import shipped_motion
from evomotion.studies.humanoid_walk.problem import HumanoidWalkConfig

cli = study_cli("humanoid-walk-open-loop")


@pytest.fixture()
def no_replay(monkeypatch):
    from evomotion.studies.humanoid_walk import compare

    def replay(*a, **k):
        raise AssertionError("a motion was replayed before the run folder was checked")

    monkeypatch.setattr(compare, "measure", replay)


def _run(d: Path, config: str) -> Path:
    """A run folder with ``config`` as its config.toml and a NAO motion as best.motion."""
    d.mkdir()
    (d / "config.toml").write_text(config)
    (d / "best.motion").write_text(format_motion(shipped_motion("TurnLeft40")))
    return d


def test_compare_refuses_another_studys_run_naming_it(tmp_path, no_replay):
    kick = _run(tmp_path / "kick", 'study = "biped-kick"\n')
    one_error(*cli("compare", kick), "biped-kick", "humanoid-walk-open-loop")
    one_error(*cli("compare", tmp_path), "config.toml")  # not a run folder at all


def test_compare_refuses_a_walk_of_another_robot(tmp_path, no_replay):
    op3 = _run(tmp_path / "op3", 'study = "humanoid-walk-open-loop"\n[problem]\nrobot = "op3"\n')
    one_error(*cli("compare", op3), "op3")


@pytest.mark.parametrize("args,needle", [(["--hold", "nan"], "--hold"),
                                         (["--hold", "1e300"], "--hold"),
                                         (["--trials", "-1"], "--trials")])
def test_compare_refuses_non_physical_numbers(tmp_path, no_replay, args, needle):
    walk = _run(tmp_path / "walk", 'study = "humanoid-walk-open-loop"\n')
    one_error(*cli("compare", walk, *args), needle)


@pytest.mark.parametrize("key,value", [("heading_weight", 1e300), ("energy_weight", 1e300),
                                       ("heading_tolerance_rad_per_m", 1e300),
                                       ("fall_height_m", 1e300), ("segment_s", 1e300),
                                       ("walk_s", float("nan"))])
def test_config_floats_have_a_documented_range(key, value):
    with pytest.raises(InputError, match=f"problem.{key}: expected"):
        HumanoidWalkConfig(**{key: value}).validate()
