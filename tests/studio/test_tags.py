"""A run's tags (issue 35: name/tag a run): checked when typed, kept in ``tags.txt``, read
without blocking or trusting the file, shown in the runs list and offered by compare."""

from __future__ import annotations

import os

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.errors import InputError
from evomotion.studio import compare, data
from evomotion.studio.tags import MAX_TAGS, NAME, TAG, parse_tags, read_tags, write_tags


def test_tags_are_words_separated_by_commas_or_spaces():
    assert parse_tags("baseline, lr-0.1  v2+gpu,baseline") == ("baseline", "lr-0.1", "v2+gpu")
    assert parse_tags("  ") == ()
    for bad, named in (("ok, no/slash", "no/slash"), ("-dash", "-dash"), ("x" * 33, "x" * 20),
                       ("a=b", "a=b"), ("naïve", "naïve")):
        with pytest.raises(InputError, match="tag") as e:
            parse_tags(bad)
        assert named in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(InputError, match=f"at most {MAX_TAGS}"):
        parse_tags(" ".join(f"t{i}" for i in range(MAX_TAGS + 1)))
    with pytest.raises(InputError, match="expected text"):
        parse_tags(["a"])


def test_written_tags_read_back_and_no_tags_remove_the_file(tmp_path):
    write_tags(tmp_path, ["b", "a", "b"])
    assert (tmp_path / NAME).read_text() == "b\na\n"
    assert read_tags(tmp_path) == ("b", "a")
    with pytest.raises(InputError):
        write_tags(tmp_path, ["fine", "not fine"])
    assert read_tags(tmp_path) == ("b", "a")  # a refused edit changes nothing
    write_tags(tmp_path, [])
    assert not (tmp_path / NAME).exists() and read_tags(tmp_path) == ()


def test_a_hostile_tags_file_reads_as_no_tags_without_blocking(tmp_path):
    os.mkfifo(tmp_path / NAME)  # opened for reading it would block
    assert read_tags(tmp_path) == ()
    (tmp_path / NAME).unlink()
    (tmp_path / NAME).write_bytes(b"ok\n" * 5000)  # over the size limit
    assert read_tags(tmp_path) == ()
    (tmp_path / NAME).write_bytes(b"good\n\xff\xfe bad/one\n\x00\nalso-good\n")
    assert read_tags(tmp_path) == ("good", "also-good")


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=600))
def test_any_tags_file_reads_as_valid_tags(tmp_path_factory, raw):
    d = tmp_path_factory.mktemp("t")
    (d / NAME).write_bytes(raw)
    tags = read_tags(d)
    assert len(tags) <= MAX_TAGS and len(set(tags)) == len(tags)
    assert all(TAG.fullmatch(t) for t in tags)
    assert parse_tags(" ".join(tags)) == tags  # what is shown can be saved again


def test_the_runs_list_and_compare_carry_the_tags(tmp_path):
    for name, tags in (("a", ["seed-sweep", "v1"]), ("b", [])):
        (tmp_path / name).mkdir()
        (tmp_path / name / "config.toml").write_text('study = "functions"\n')
        write_tags(tmp_path / name, tags)
    rows = {r.name: r.row() for r in data.list_runs(tmp_path)}
    assert rows["a"]["tags"] == ("seed-sweep", "v1") and rows["b"]["tags"] == ()
    flat = compare.configs([tmp_path / "a", tmp_path / "b"])
    assert [f["tags"] for f in flat] == ["seed-sweep v1", compare.MISSING]
    assert "tags" in compare.group_choices(flat)
    assert compare.group_label(flat[0], "tags") == "functions · tags = seed-sweep v1"
