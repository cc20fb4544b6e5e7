"""Scenario parser: the paper's example, bundled files and every malformed case."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.errors import FileFormatError
from evomotion.studies.arm_ik.scenario import (
    SCENARIO_DIR,
    bundled_names,
    load_scenario,
    parse_scenario_text,
)

PAPER = (SCENARIO_DIR / "paper_example.scen").read_text()


def test_paper_example_parses_exactly():
    s = parse_scenario_text(PAPER, "paper.scen")
    assert (s.width, s.height) == (10, 5)
    np.testing.assert_array_equal(s.start, [5, 4])
    np.testing.assert_array_equal(s.targets, [[1, 1], [9, 1]])
    np.testing.assert_array_equal(s.arm.length, [3, 1])
    assert [f.n_bones for f in s.fingers] == [2, 2]
    assert len(s.obstacles) == 2
    np.testing.assert_array_equal(s.obstacles[0], [[1, 3], [2, 4], [4, 4]])
    assert s.obstacles[1].shape == (5, 2)
    assert s.obstacle_segments().shape == (6, 2, 2)


def test_bundled_scenarios_load_and_extra_bone_pair_differs_only_in_arm():
    names = bundled_names()
    assert {"paper_example", "three_fingers", "three_fingers_extra_bone", "corridor",
            "four_fingers", "unreachable"} <= set(names)
    for n in names:
        assert load_scenario(n).summary().startswith(f"scenario {n}")
    a, b = load_scenario("three_fingers"), load_scenario("three_fingers_extra_bone")
    assert b.arm.n_bones == a.arm.n_bones + 1
    np.testing.assert_array_equal(b.arm.length[: a.arm.n_bones], a.arm.length)
    np.testing.assert_array_equal(a.targets, b.targets)
    assert all(np.array_equal(p, q) for p, q in zip(a.obstacles, b.obstacles, strict=True))


def _lines() -> list[str]:
    return [ln for ln in PAPER.splitlines()]


def _replace(old_line_no: int, new: str | None) -> str:
    """The example text with (1-based) line ``old_line_no`` replaced (or removed if None)."""
    lines = _lines()
    if new is None:
        del lines[old_line_no - 1]
    else:
        lines[old_line_no - 1] = new
    return "\n".join(lines) + "\n"


def _line_of(text: str, occurrence: int = 1) -> int:
    """1-based line number of the ``occurrence``-th line equal to ``text`` in the example."""
    hits = [i + 1 for i, ln in enumerate(_lines()) if ln == text]
    return hits[occurrence - 1]


@pytest.mark.parametrize(
    ("line_text", "occ", "new", "expect"),
    [
        ("10", 1, "ten", "non-numeric"),  # board width not a number
        ("10", 1, "-3", "board width > 0"),
        ("5 4", 1, "5", "start point"),  # wrong number of values
        ("5 4", 1, "11 4", "inside the board"),  # start outside the board
        ("2", 1, "2.5", "number of targets (one integer)"),
        ("9 1", 1, "9 1 3", "target 2"),
        ("3 0 360", 1, "-3 0 360", "length > 0"),  # negative length
        ("1 0 360", 1, "1 200 100", "0 <= min <= max <= 360"),  # min > max
        ("1 0 360", 1, "1 0 400", "0 <= min <= max <= 360"),
        ("3 0 360", 2, "3 0", "finger 1 bone 1"),
        ("3", 1, "1", "number of points of obstacle 1 >= 2"),  # fewer than 2 points
        ("1 3", 1, "1 three", "non-numeric"),
    ],
)
def test_malformed_line_names_file_line_and_expectation(line_text, occ, new, expect):
    no = _line_of(line_text, occ)
    with pytest.raises(FileFormatError) as e:
        parse_scenario_text(_replace(no, new), "bad.scen")
    assert e.value.line == no
    assert e.value.path == "bad.scen"
    assert expect in str(e.value)
    assert str(e.value).startswith(f"bad.scen:{no}: expected")
    assert "\n" not in str(e.value)


def test_missing_count_at_end_of_file():
    text = "\n".join(_lines()[: _line_of("# Number of obstacles")]) + "\n"
    with pytest.raises(FileFormatError, match="number of obstacles, got end of file"):
        parse_scenario_text(text, "short.scen")


def test_missing_obstacle_points_and_extra_lines():
    lines = _lines()
    with pytest.raises(FileFormatError, match="obstacle 2 point 5"):
        parse_scenario_text("\n".join(lines[:-1]), "x.scen")
    with pytest.raises(FileFormatError, match="expected end of file"):
        parse_scenario_text(PAPER + "1 2\n", "x.scen")


def test_comments_and_blank_lines_are_skipped():
    text = "# c\n\n  # indented comment\n" + PAPER.replace("\n5 4\n", "\n\n5 4   \n")
    s = parse_scenario_text(text)
    np.testing.assert_array_equal(s.start, [5, 4])


def test_unknown_file_lists_bundled(tmp_path):
    with pytest.raises(FileFormatError, match="bundled name"):
        load_scenario(tmp_path / "nope.scen")
    (tmp_path / "bin.scen").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(FileFormatError, match="UTF-8"):
        load_scenario(tmp_path / "bin.scen")


def test_old_bundled_name_loads_the_paper_example():
    """``seed_example`` is the old name of ``paper_example`` (configs from before issue 32)."""
    old, new = load_scenario("seed_example"), load_scenario("paper_example")
    assert old.summary() == new.summary()
    np.testing.assert_array_equal(old.targets, new.targets)


def test_reach_intervals():
    s = load_scenario("paper_example")
    assert s.arm.reach() == (2.0, 4.0)
    assert s.fingers[0].reach() == (0.0, 6.0)
