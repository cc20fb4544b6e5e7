"""biped-kick against hostile input (issue 31): ``plan``, ``play`` and ``study`` refuse
non-physical numbers, another study's run, hostile files and unwritable outputs in one
line, before any work; the problem's floats have documented ranges."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from evomotion.errors import InputError
from evomotion.studies.biped_kick.motion import GENES, START
from evomotion.studies.biped_kick.problem import KickConfig

X0 = [START[g[0]] for g in GENES]
from hostile_cli import one_error, study_cli  # noqa: E402 - tests/studies/conftest.py

cli = study_cli("biped-kick")


@pytest.fixture()
def no_work(monkeypatch):
    """Any simulation, plot or experiment run is a test failure (refusals come first)."""
    from evomotion.studies.biped_kick import experiment, play, views

    def work(*a, **k):
        raise AssertionError("the work started before the input was checked")

    for mod, name in ((play, "play"), (views, "plot_kick_plan"), (experiment, "optimise")):
        monkeypatch.setattr(mod, name, work)


# -- 1. accepted when it should be refused ------------------------------------------------

@pytest.mark.parametrize("args,needle", [
    (["--ball", "nan", "nan"], "--ball"),
    (["--ball", "1e300", "0"], "--ball"),
    (["--goal", "inf", "0"], "--goal"),
    (["--robot", "0", "0", "nan"], "--robot"),
    (["--robot", "0", "0", "1e6"], "--robot"),
    (["--radius", "nan"], "--radius"),
    (["--radius", "1e300"], "--radius"),
    (["--goal", "1.5", "0.5"], "--goal"),
])
def test_plan_refuses_non_physical_numbers(tmp_path, no_work, args, needle):
    one_error(*cli("plan", "--out", tmp_path / "p.png", *args), needle)
    assert not (tmp_path / "p.png").exists()


@pytest.mark.parametrize("args,needle", [
    (["--robot", "0", "0", "50"], "--robot"),
    (["--target", "nan", "0"], "--target"),
    (["--ball", "1", "-inf"], "--ball"),
])
def test_play_refuses_non_physical_numbers(tmp_path, no_work, args, needle):
    one_error(*cli("play", *args), needle)


def _run(d: Path, study: str) -> Path:
    d.mkdir(parents=True)
    (d / "config.toml").write_text(f'study = "{study}"\n')
    return d


def test_play_refuses_another_studys_run_naming_it(tmp_path, no_work):
    arm = _run(tmp_path / "arm", "arm-ik")
    (arm / "best.json").write_text(json.dumps({"genome": X0}))  # no "study" key of its own
    one_error(*cli("play", "--kick", arm), "--kick", "arm-ik")
    kick = _run(tmp_path / "kick", "biped-kick")
    (kick / "repertoire").mkdir()
    (kick / "repertoire" / "index.json").write_text(json.dumps({"entries": [
        {"file": "cell-0001.motion", "cell": 1, "objective": -0.5,
         "measured": {"dx_m": 0.05, "dy_m": 0.0, "dtheta_deg": 0.0}}]}))
    one_error(*cli("play", "--walk", kick), "--walk", "biped-kick")


@pytest.mark.parametrize("index,needle", [
    ("[" * 100_000 + "]" * 100_000, "nested"),
    ('{"entries": [{"file": "cell-0001.motion", "cell": 1, "objective": -0.5, '
     '"measured": {"dx_m": 1e300, "dy_m": 0, "dtheta_deg": 0}}]}', "dx_m"),
], ids=["nested", "huge-step"])
def test_play_refuses_a_hostile_repertoire_before_walking(tmp_path, no_work, index, needle):
    rep = _run(tmp_path / "rep", "humanoid-repertoire")
    (rep / "repertoire").mkdir()
    (rep / "repertoire" / "index.json").write_text(index)
    one_error(*cli("play", "--walk", rep), "index.json", needle)


def test_a_deeply_nested_kick_file_is_one_line(tmp_path, no_work):
    f = tmp_path / "best.json"
    f.write_text('{"genome": ' + "[" * 100_000 + "]" * 100_000 + "}")
    one_error(*cli("play", "--kick", f), "best.json")
    with pytest.raises(InputError, match="nested"):
        from evomotion.studies.biped_kick.play import read_kick

        read_kick(f)


@pytest.mark.parametrize("args,needle", [
    (["--budget", str(10**12)], "--budget"),
    (["--kicks", str(10**9)], "--kicks"),
    (["--seeds", str(10**6)], "--seeds"),
    (["--aim", "nan"], "--aim"),
    (["--aim", "90"], "--aim"),
])
def test_study_refuses_budgets_beyond_its_documented_limits(tmp_path, no_work, args, needle):
    one_error(*cli("study", "--out", tmp_path / "s", *args), needle)
    assert not (tmp_path / "s").exists()


# -- 2. outputs checked before the work; no folder made for a mistyped path --------------

def test_plan_out_into_a_missing_folder_is_refused_not_made(tmp_path, no_work):
    one_error(*cli("plan", "--out", tmp_path / "no" / "such" / "p.png"), "does not exist")
    assert not (tmp_path / "no").exists()
    one_error(*cli("plan", "--out", tmp_path / "p.txt"), ".png")


def test_plan_and_play_outputs_that_are_not_files_are_refused(tmp_path, no_work):
    dev = tmp_path / "dev.png"
    dev.symlink_to(os.devnull)
    one_error(*cli("plan", "--out", dev), "device")
    (tmp_path / "dir.png").mkdir()
    one_error(*cli("plan", "--out", tmp_path / "dir.png"), "folder")
    fifo = tmp_path / "v.mp4"
    os.mkfifo(fifo)
    one_error(*cli("play", "--video", fifo), "FIFO")
    one_error(*cli("play", "--video", tmp_path / "no" / "v.mp4"), "does not exist")


def test_study_outputs_are_checked_before_any_run(tmp_path, no_work):
    one_error(*cli("study", "--out", tmp_path / "no" / "such"), "does not exist")
    assert not (tmp_path / "no").exists()
    out = tmp_path / "s"
    (out / "results.json").mkdir(parents=True)
    one_error(*cli("study", "--out", out, "--budget", "4"), "results.json")


def test_plan_writes_its_picture_atomically(tmp_path):
    out = tmp_path / "p.svg"
    code, err = cli("plan", "--out", out)
    assert code == 0, err
    first = out.read_bytes()
    assert cli("plan", "--out", out)[0] == 0
    assert out.read_bytes() == first  # the same bytes (no date in the SVG)
    assert [p.name for p in tmp_path.iterdir()] == ["p.svg"]  # no temporary left


# -- 4. config ranges ---------------------------------------------------------------------

@pytest.mark.parametrize("key,value", [("w_angle_m_per_rad", 1e300), ("w_time_m_per_s", 1e300),
                                       ("roll_after_s", 1e300), ("zmp_margin_m", 1e300),
                                       ("fall_height_m", 1e300), ("roll_after_s", -1.0)])
def test_config_floats_have_a_documented_range(key, value):
    with pytest.raises(InputError, match=f"problem.{key}: expected"):
        KickConfig(**{key: value}).validate()
