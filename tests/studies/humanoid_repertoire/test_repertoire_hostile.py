"""humanoid-repertoire against hostile input (issue 31): every command refuses bad numbers,
another study's run, hostile index and archive files and unwritable outputs in one line,
before any work; the repertoire it writes is a function of the archive alone.

The run folders here are made by hand (config.toml + archive.npz of a few steps), so the tests
take seconds; ``test_repertoire.py`` runs the study itself.
"""

from __future__ import annotations

import io
import json
import os
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hostile_cli import one_error, study_cli  # tests/studies/conftest.py

from evomotion.errors import InputError
from evomotion.studies.humanoid_repertoire import step
from evomotion.studies.humanoid_repertoire.problem import (
    MEASURES,
    HumanoidRepertoireConfig,
)

cli = study_cli("humanoid-repertoire")


def _archive(path: Path, cells: dict[int, tuple[float, float, float]],
             objective: float = -0.5) -> None:
    """An ``archive.npz`` of the NAO's grid with the default step in ``cells`` (cell index ->
    measured dx m, dy m, dtheta deg)."""
    bins = np.array(MEASURES.bins)
    n = int(np.prod(bins))
    idx = np.array(sorted(cells), dtype=np.int64)
    meas = np.array([cells[c] for c in idx], dtype=float).reshape(-1, 3)
    genes = np.repeat(step.DEFAULT[None], len(idx), axis=0)
    # each cell its own step (a different motion file), inside the genome's bounds as the
    # search keeps it (a measured dx of 0.5 m is an elite that left the box)
    genes[:, 0] = np.clip(meas[:, 0], step.LOWER[0], step.UPPER[0])
    centres = np.zeros((n, 3))
    np.savez(path, kind=np.array("grid"), bins=bins.astype(np.int64), cells=np.array(n),
             lower=MEASURES.lower, upper=MEASURES.upper,
             measure_names=np.array(list(MEASURES.names)), cell=idx, centre=centres[idx],
             solution=genes, objective=np.full(len(idx), objective), measures=meas,
             all_centres=centres)


def _run(d: Path, study: str = "humanoid-repertoire", hold: float = 0.2,
         cells: dict | None = None) -> Path:
    """A run folder of ``study`` holding an archive (as a run leaves it)."""
    d.mkdir(parents=True, exist_ok=True)
    (d / "config.toml").write_text(f'study = "{study}"\n\n[problem]\nhold_s = {hold}\n'
                                   if study == "humanoid-repertoire" else
                                   f'study = "{study}"\n')
    _archive(d / "archive.npz", cells or {10: (0.05, 0.0, 0.0), 20: (0.0, 0.03, 5.0),
                                          30: (0.08, -0.02, -10.0)})
    return d


@pytest.fixture()
def run(tmp_path):
    d = _run(tmp_path / "run")
    code, err = cli("export", d)
    assert code == 0, err
    return d


# -- 1. accepted when it should be refused ------------------------------------------------

@pytest.mark.parametrize("hold", ["nan", "inf", "-1", "1e300"])
def test_export_refuses_a_hold_that_is_not_a_time(run, hold):
    before = (run / "repertoire" / "index.json").read_bytes()
    one_error(*cli("export", run, "--hold", hold), "--hold")
    assert (run / "repertoire" / "index.json").read_bytes() == before


@pytest.mark.parametrize("args,needle", [
    (["pick", "--dx", "nan"], "--dx"),
    (["pick", "--dx", "0", "--dtheta", "inf"], "--dtheta"),
    (["pick", "--dx", "1e300"], "--dx"),
    (["walk-to", "--x", "nan"], "--x"),
    (["walk-to", "--x", "0.1", "--y", "-1e300"], "--y"),
    (["walk-to", "--x", "0.1", "--theta", "1e9"], "--theta"),
])
def test_numbers_that_are_not_physical_are_refused(run, args, needle):
    one_error(*cli(args[0], run, *args[1:]), needle)


def test_another_studys_run_is_refused_naming_it(tmp_path):
    kick = _run(tmp_path / "kick", study="biped-kick")
    (kick / "repertoire").mkdir()
    (kick / "repertoire" / "index.json").write_text(json.dumps({"entries": [
        {"file": "cell-0010.motion", "cell": 10, "objective": -0.5,
         "measured": {"dx_m": 0.05, "dy_m": 0.0, "dtheta_deg": 0.0}}]}))
    for args in (["pick", kick, "--dx", "0"], ["walk-to", kick, "--x", "0.1"],
                 ["export", kick]):
        one_error(*cli(*args), "biped-kick", "humanoid-repertoire")
    one_error(*cli("pick", tmp_path / "nothing", "--dx", "0"), "nothing")


@pytest.mark.parametrize("index,needle", [
    ("[" * 100_000 + "]" * 100_000, "nested"),
    ('{"entries": [{"file": "cell-0010.motion", "cell": 10, "objective": -0.5, '
     '"measured": {"dx_m": 1e300, "dy_m": 0, "dtheta_deg": 0}}]}', "dx_m"),
    ('{"entries": [{"file": "cell-0010.motion", "cell": 10, "objective": -0.5, '
     '"measured": {"dx_m": NaN, "dy_m": 0, "dtheta_deg": 0}}]}', "finite"),
    ('{"entries": [{"file": "cell-0010.motion", "cell": 10, "objective": -1e308, '
     '"measured": {"dx_m": 0.1, "dy_m": 0, "dtheta_deg": 0}}]}', "objective"),
    ('{"entries": [{"file": "../../etc/passwd", "cell": 10, "objective": 0, '
     '"measured": {"dx_m": 0.1, "dy_m": 0, "dtheta_deg": 0}}]}', "file"),
], ids=["nested", "huge-step", "nan", "huge-objective", "path"])
def test_a_hostile_index_is_one_line(run, index, needle):
    (run / "repertoire" / "index.json").write_text(index)
    for args in (["pick", run, "--dx", "0"], ["walk-to", run, "--x", "0.3"]):
        one_error(*cli(*args), "index.json", needle)


def test_huge_measured_steps_are_refused_not_overflowing(run):
    """Steps of 1e300 m used to overflow the planner (OverflowError)."""
    from evomotion.studies.humanoid_repertoire.step_planning import plan

    doc = json.loads((run / "repertoire" / "index.json").read_text())
    for e in doc["entries"]:
        e["measured"]["dx_m"] = 1e300
    (run / "repertoire" / "index.json").write_text(json.dumps(doc))
    one_error(*cli("walk-to", run, "--x", "5"), "dx_m")
    with pytest.raises(InputError):
        plan(np.array([[np.inf, 0, 0]]), np.array([1.0, 0, 0]))


def test_a_hostile_archive_is_one_line(run):
    header = io.BytesIO()  # a header declaring a 72.8 TiB array, and no data
    np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False,
                                                  "shape": (10**8, 10**5)})
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        z.writestr("cell.npy", header.getvalue())
    (run / "archive.npz").write_bytes(buf.getvalue())
    one_error(*cli("export", run), "archive.npz")


def _edit_archive(run: Path, edit) -> None:
    with np.load(run / "archive.npz") as z:
        a = {k: z[k] for k in z.files}
    edit(a)
    np.savez(run / "archive.npz", **a)


def test_archived_genes_of_another_count_or_outside_the_bounds_are_one_line(run):
    """An archive edited by hand: elites with 7 genes (a traceback before) or a gene of 1e300
    (exported before, with a numpy overflow warning) are refused naming the file."""
    _edit_archive(run, lambda a: a.update(solution=a["solution"][:, :7]))
    one_error(*cli("export", run), "'solution' holds 7 genes per cell, expected 8")

    def huge(a):
        a["solution"][0, 0] = 1e300
    _edit_archive(run, lambda a: a.update(solution=np.repeat(step.DEFAULT[None], 3, axis=0)))
    _edit_archive(run, huge)
    one_error(*cli("export", run), "cell 10's genes lie outside the genome's bounds")


def test_an_archive_that_fills_a_cell_twice_is_one_line(run):
    _edit_archive(run, lambda a: a.update(cell=np.array([10, 10, 30])))
    one_error(*cli("export", run), "archive.npz: inconsistent archive arrays (expected n "
                                   "distinct filled cells")


@pytest.mark.parametrize("damage", ["missing", "garbage"])
def test_pick_refuses_a_step_whose_motion_is_missing_or_no_motion(run, damage):
    """``pick`` names a .motion that walk-to could play: one that is gone or is no motion is
    refused in one line (it was reported as the answer before)."""
    index = json.loads((run / "repertoire" / "index.json").read_text())
    for e in index["entries"]:
        f = run / "repertoire" / e["file"]
        f.unlink() if damage == "missing" else f.write_bytes(os.urandom(2000))
    one_error(*cli("pick", run, "--dx", "0.05"), "cell-")


# -- 2. writes: checked before the work, never through a link out of the run -------------

def test_walk_to_outputs_are_checked_before_planning(run, tmp_path, monkeypatch):
    import evomotion.sim.robots.nao.replay as replay

    def simulated(*a, **k):
        raise AssertionError("the walk was simulated before its outputs were checked")

    monkeypatch.setattr(replay, "replay_motion", simulated)
    one_error(*cli("walk-to", run, "--x", "0.1", "--out", tmp_path / "no" / "w.motion"),
              "does not exist")
    one_error(*cli("walk-to", run, "--x", "0.1", "--video", tmp_path / "no" / "w.mp4"),
              "does not exist")
    one_error(*cli("walk-to", run, "--x", "0.1", "--video", tmp_path / "w.gif"), ".mp4")
    one_error(*cli("walk-to", run, "--x", "0.1", "--out", "/dev/null"), "device")
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    one_error(*cli("walk-to", run, "--x", "0.1", "--out", fifo), "FIFO")
    assert not (tmp_path / "no").exists()


def test_a_repertoire_folder_that_links_out_of_the_run_is_refused(tmp_path):
    outside = tmp_path / "outside"
    outside.mkdir()
    d = _run(tmp_path / "run")
    (d / "repertoire").symlink_to(outside)
    one_error(*cli("export", d), "repertoire")
    assert list(outside.iterdir()) == []


# -- 3. the repertoire is a function of the archive ---------------------------------------

def _tree(d: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted((d / "repertoire").iterdir())
            if p.is_file()}


def test_export_rebuilds_exactly_what_the_run_wrote(tmp_path):
    """``export`` with no --hold records the run's own hold (it used to record 2 s), so the
    rebuilt repertoire is the run's, byte for byte."""
    from evomotion.studies.humanoid_repertoire.artifacts import write_repertoire

    d = _run(tmp_path / "run", hold=0.2)
    write_repertoire(d, HumanoidRepertoireConfig(hold_s=0.2).hold_s)  # the run's hook
    written = _tree(d)
    assert cli("export", d)[0] == 0
    assert _tree(d) == written
    assert json.loads(written["index.json"])["hold_s"] == 0.2


def test_the_repertoire_holds_exactly_the_current_archive_and_is_idempotent(tmp_path):
    """Cells of an earlier archive that are no longer in it are removed (a stale cell whose
    elite left the box); a folder named like a cell is left alone; writing twice changes
    nothing."""
    a = _run(tmp_path / "a", cells={10: (0.05, 0.0, 0.0), 20: (0.0, 0.03, 5.0),
                                    30: (0.08, -0.02, -10.0)})
    assert cli("export", a)[0] == 0
    (a / "repertoire" / "cell-9999.motion").mkdir()  # not ours to remove
    (a / "repertoire" / "notes.txt").write_text("mine")
    cells = {20: (0.0, 0.03, 5.0), 40: (-0.05, 0.01, 20.0), 30: (0.5, 0.0, 0.0)}  # 30: outside
    _archive(a / "archive.npz", cells)
    b = _run(tmp_path / "b", cells=cells)
    for _ in range(2):
        assert cli("export", a)[0] == 0
        assert cli("export", b)[0] == 0
        got = _tree(a)
        assert got.pop("notes.txt") == b"mine" and (a / "repertoire" / "cell-9999.motion").is_dir()
        assert got == _tree(b)
        assert sorted(got) == ["cell-0020.motion", "cell-0040.motion", "index.json",
                               "ready.motion"]


# -- 4. config ranges ---------------------------------------------------------------------

@pytest.mark.parametrize("key,value", [("hold_s", 1e300), ("segment_s", 1e300),
                                       ("effort_weight", 1e300), ("fall_height_m", 1e300),
                                       ("hold_s", -1.0), ("fall_height_m", float("nan"))])
def test_config_floats_have_a_documented_range(key, value):
    with pytest.raises(InputError, match=f"problem.{key}: expected"):
        HumanoidRepertoireConfig(**{key: value}).validate()
