"""A repertoire's ``index.json`` and cell files (issue 31): read with bounds (size, nesting,
finite numbers), every field checked, cell files only inside the repertoire folder; every
failure one :class:`InputError` line, never a RecursionError or a NaN step."""

from __future__ import annotations

import json
import os
import threading
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from evomotion.errors import InputError
from evomotion.sim import repertoire
from evomotion.sim.motion import Motion, format_motion
from evomotion.sim.repertoire import read_cell, read_index

ENTRY = {"cell": 3, "file": "cell-0003.motion", "objective": -0.5,
         "measured": {"dx_m": 0.05, "dy_m": -0.01, "dtheta_deg": 4.0},
         "centre": [0.05, 0.0, 0.0], "genes": {"shift_s": 0.4}}
INDEX = {"robot": "nao", "stepper": "closed_form", "box": {"lower": [-0.1, -0.1, -30],
                                                  "upper": [0.1, 0.1, 30]},
         "measures": ["dx_m", "dy_m", "dtheta_deg"], "cells": [5, 5, 5], "archived": 1,
         "fallen": 0, "outside_box": 0, "hold_s": 0.5, "entries": [ENTRY]}


def write(tmp_path: Path, text: str) -> Path:
    folder = tmp_path / "run" / "repertoire"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "index.json").write_text(text)
    return folder


def refused(tmp_path: Path, text: str, *fragments: str) -> str:
    write(tmp_path, text)
    with pytest.raises(InputError) as e:
        read_index(tmp_path / "run")
    msg = str(e.value)
    assert "\n" not in msg and "index.json" in msg, msg
    for f in fragments:
        assert f in msg, msg
    return msg


def with_entry(**change) -> str:
    entry = {**ENTRY, **change}
    return json.dumps({**INDEX, "entries": [entry]})


def test_a_good_index_reads(tmp_path):
    folder = write(tmp_path, json.dumps(INDEX))
    got_folder, index = read_index(tmp_path / "run")
    assert got_folder == folder and index["entries"][0]["cell"] == 3


@pytest.mark.parametrize("text", ['{"entries": ' + "[" * 100_000 + "]" * 100_000 + "}",
                                  "{" * 50_000], ids=["array", "object"])
def test_deeply_nested_json_is_one_line(tmp_path, text):
    refused(tmp_path, text, "expected JSON nested at most 8 deep")


@pytest.mark.parametrize("text,fragment", [
    (json.dumps({**INDEX, "hold_s": 0.5}).replace("0.5,", "NaN,", 1), "finite numbers"),
    (json.dumps(INDEX).replace('"hold_s": 0.5', '"hold_s": Infinity'), "finite numbers"),
    (json.dumps(INDEX).replace('"hold_s": 0.5', '"hold_s": 1e999'), "finite numbers"),
    (json.dumps({**INDEX, "hold_s": 1e300}), "'hold_s' a number of seconds from 0 to 60"),
    (json.dumps({**INDEX, "hold_s": "0.5"}), "'hold_s' a number of seconds"),
    (with_entry(objective=1e300), "entry 0: expected 'objective' a number within +-1000"),
    (with_entry(measured={"dx_m": 1e300, "dy_m": 0, "dtheta_deg": 0}),
     "measured dx_m a number within +-1 m"),
    (with_entry(measured={"dx_m": 0, "dy_m": 0, "dtheta_deg": True}), "dtheta_deg"),
    (with_entry(measured=[1, 2, 3]), "entry 0: expected an object"),
    (with_entry(cell=-1), "'cell' a non-negative integer"),
    (with_entry(cell=10**40), "'cell' a non-negative integer"),
    (json.dumps({**INDEX, "entries": []}), "the repertoire is empty"),
    (json.dumps({**INDEX, "entries": {}}), "a list 'entries'"),
    (json.dumps({**INDEX, "robot": "nao\nerror: forged"}), "'robot' a printable name"),
    (json.dumps({**INDEX, "is_nao": "yes"}), "'is_nao' true or false"),
    (json.dumps({**INDEX, "stepper": "magic"}), "'stepper' one of closed_form, numerical"),
    ("[]", "a list 'entries'"),
    ("{", "invalid JSON"),
])
def test_bad_fields_are_one_line(tmp_path, text, fragment):
    refused(tmp_path, text, fragment)


@pytest.mark.parametrize("name", ["../outside.motion", "/etc/passwd", "sub/cell.motion",
                                  "..motion", "cell-0003.txt", "", 3, None, "a\nb.motion"])
def test_cell_files_outside_the_folder_are_refused(tmp_path, name):
    refused(tmp_path, with_entry(file=name), "entry 0: expected 'file' a .motion file name")
    folder = tmp_path / "run" / "repertoire"
    with pytest.raises(InputError, match="expected a cell file name"):
        read_cell(folder, {"file": name})


def test_too_many_entries_are_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(repertoire, "MAX_ENTRIES", 2)
    refused(tmp_path, json.dumps({**INDEX, "entries": [ENTRY] * 3}), "at most 2 entries")


def test_huge_index_and_fifo_index_are_refused_without_blocking(tmp_path):
    folder = write(tmp_path, "{}")
    (folder / "index.json").unlink()
    with open(folder / "index.json", "wb") as f:
        f.truncate(2**40)
    with pytest.raises(InputError, match="at most 16 MiB"):
        read_index(tmp_path / "run")
    (folder / "index.json").unlink()
    os.mkfifo(folder / "index.json")
    out: dict = {}

    def read():
        try:
            read_index(tmp_path / "run")
        except InputError as e:
            out["e"] = str(e)

    t = threading.Thread(target=read, daemon=True)
    t.start()
    t.join(10)
    assert not t.is_alive() and "got a FIFO" in out.get("e", "")


def test_read_cell_reads_only_inside_the_folder_and_bounded(tmp_path):
    folder = write(tmp_path, json.dumps(INDEX))
    good = Motion(("HeadYaw",), [0, 40], [[0.0], [0.1]])
    (folder / "cell-0003.motion").write_text(format_motion(good))
    assert read_cell(folder, ENTRY).values.shape == (2, 1)
    (tmp_path / "secret.motion").write_text(format_motion(good))
    (folder / "cell-0004.motion").symlink_to(tmp_path / "secret.motion")
    with pytest.raises(InputError, match="expected a file inside"):
        read_cell(folder, {"file": "cell-0004.motion"})
    os.mkfifo(folder / "cell-0005.motion")
    with pytest.raises(InputError, match="got a FIFO"):
        read_cell(folder, {"file": "cell-0005.motion"})


json_values = st.recursive(
    st.none() | st.booleans() | st.floats(allow_nan=False) | st.integers()
    | st.text(max_size=12) | st.sampled_from(["cell-0001.motion", "../x.motion"]),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(
        st.sampled_from(["entries", "file", "cell", "objective", "measured", "dx_m", "dy_m",
                         "dtheta_deg", "hold_s", "robot", "is_nao", "stepper", "x"]), inner,
        max_size=4),
    max_leaves=12)


@settings(max_examples=200, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(json_values | st.text(max_size=40))
def test_fuzz_index_only_input_errors(tmp_path, doc):
    text = doc if isinstance(doc, str) and not doc.startswith("cell") else json.dumps(doc)
    write(tmp_path, text)
    try:
        folder, index = read_index(tmp_path / "run")
    except InputError as e:
        assert "\n" not in str(e)
        return
    for e in index["entries"]:  # what readers of an accepted index rely on
        assert isinstance(e["file"], str) and "/" not in e["file"]
        assert all(abs(e["measured"][k]) <= 180 for k in ("dx_m", "dy_m", "dtheta_deg"))
