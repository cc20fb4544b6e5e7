"""Map readers, writer, endpoint checks, random maps and the paper's cell numbering."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.errors import FileFormatError, InputError
from evomotion.studies.grid_path.maps import (
    cell_centre,
    cell_number,
    random_map,
    read_map,
    write_map,
)
from evomotion.studies.grid_path.problem import BUNDLED, load_map

MAI = "type octile\nheight 3\nwidth 4\nmap\n....\n.T.@\n.@..\n"


def test_read_movingai_row0_is_top(tmp_path):
    p = tmp_path / "a.map"
    p.write_text(MAI)
    m = read_map(p)
    assert (m.width, m.height, m.start, m.goal) == (4, 3, (0, 0), (3, 2))
    assert m.blocked[0].tolist() == [False, True, False, False]  # bottom row = last line
    assert m.blocked[1].tolist() == [False, True, False, True] and not m.blocked[2].any()
    out = tmp_path / "b.map"
    write_map(out, m.blocked)
    assert np.array_equal(read_map(out, goal=(2, 2)).blocked, m.blocked)


def test_read_01_grid_and_custom_endpoints(tmp_path):
    p = tmp_path / "g.txt"
    p.write_text("0 0 0\n0 1 0\n0 0 0\n")
    m = read_map(p, start=(2, 0), goal=(0, 2))
    assert m.blocked[1, 1] and m.blocked.sum() == 1 and m.start == (2, 0)


@pytest.mark.parametrize(("text", "line", "what"), [
    ("type octile\nheight 3\nwidth 4\nmap\n....\n..x.\n....\n", 6, "expected only"),
    ("type octile\nheight 3\nwidth 4\nmap\n....\n...\n....\n", 6, "row of 4"),
    ("type octile\nheight 4\nwidth 4\nmap\n....\n....\n....\n", 7, "expected 4 map rows"),
    ("type octile\nheigth 3\nwidth 4\nmap\n", 2, "expected 'type T'"),
    ("type octile\nheight 3\nwidth 4\n", 3, "'map' line"),
    ("0 1\n0 2\n", 2, "'0' and '1'"),
])
def test_malformed_maps_name_file_and_line(tmp_path, text, line, what):
    p = tmp_path / "bad.map"
    p.write_text(text)
    with pytest.raises(FileFormatError, match=what) as e:
        read_map(p)
    assert e.value.line == line and str(e.value).startswith(f"{p}:{line}:")


def test_blocked_or_cut_off_endpoints(tmp_path):
    p = tmp_path / "w.txt"
    p.write_text("000\n111\n000\n")
    with pytest.raises(InputError, match="cut off"):
        read_map(p)
    p.write_text("001\n000\n000\n")
    with pytest.raises(InputError, match="goal cell \\(2, 2\\) is blocked"):
        read_map(p)
    with pytest.raises(InputError, match="outside"):
        read_map(p, start=(5, 0))
    p.write_text("010\n100\n000\n")  # the goal's only link is a corner cut
    with pytest.raises(InputError, match="cut off"):
        read_map(p, start=(0, 0), goal=(0, 2))


def test_random_map_connected_and_density():
    m = random_map(20, 0.25, np.random.default_rng(3))
    assert m.blocked.sum() == 100 and not m.blocked[0, 0] and not m.blocked[19, 19]
    m.check()
    with pytest.raises(InputError):
        random_map(1, 0.2, np.random.default_rng(0))


def test_paper_cell_numbering_roundtrip():
    x, y = np.array([0.5, 9.2, 3.0]), np.array([0.5, 0.1, 9.9])
    P = cell_number(x, y, 10)
    assert P.tolist() == [1, 10, 94]
    cx, cy = cell_centre(P, 10)
    assert cx.tolist() == [0.5, 9.5, 3.5] and cy.tolist() == [0.5, 0.5, 9.5]


def test_bundled_and_unknown_maps():
    for name in BUNDLED:
        load_map(name).check()
    with pytest.raises(InputError, match="bundled"):
        load_map("nope")
    assert load_map("random:12:0.2:1").width == 12
    with pytest.raises(InputError, match="random:SIZE"):
        load_map("random:12:x")


def _bfs_connected(blocked, a, b):
    """The previous breadth-first search over octile moves (reference for ``connected``)."""
    from collections import deque

    from evomotion.studies.grid_path.maps import octile_moves

    seen = {tuple(a)}
    todo = deque([tuple(a)])
    while todo:
        x, y = todo.popleft()
        if (x, y) == tuple(b):
            return True
        for nx, ny, _ in octile_moves(blocked, x, y):
            if (nx, ny) not in seen:
                seen.add((nx, ny))
                todo.append((nx, ny))
    return False


def test_connected_equals_octile_search():
    from evomotion.studies.grid_path.maps import connected

    rng = np.random.default_rng(5)
    for _ in range(200):
        h, w = rng.integers(1, 9, size=2)
        blocked = rng.random((h, w)) < rng.uniform(0.1, 0.6)
        a = (int(rng.integers(w)), int(rng.integers(h)))
        b = (int(rng.integers(w)), int(rng.integers(h)))
        assert connected(blocked, a, b) == _bfs_connected(blocked, a, b)


def test_reader_is_vectorised_and_checks_the_size_first(tmp_path):
    import time

    from evomotion.studies.grid_path.maps import MAX_MAP_CELLS

    rng = np.random.default_rng(1)
    blocked = rng.random((1500, 1200)) < 0.2
    blocked[0, 0] = blocked[-1, -1] = False
    blocked[0, 1] = blocked[1, 0] = blocked[-1, -2] = blocked[-2, -1] = False
    write_map(tmp_path / "big.map", blocked)
    t = time.perf_counter()
    try:
        m = read_map(tmp_path / "big.map")
        np.testing.assert_array_equal(m.blocked, blocked)
    except InputError as e:  # a random map may be cut off; the grid was still read
        assert "cut off" in str(e)
    assert time.perf_counter() - t < 10  # the per-character reader took ~6 s here
    (tmp_path / "huge.map").write_text("type octile\nheight 100000\nwidth 100000\nmap\n")
    with pytest.raises(FileFormatError, match=f"at most {MAX_MAP_CELLS:,} cells"):
        read_map(tmp_path / "huge.map")


def test_crlf_blank_lines_and_01_separators(tmp_path):
    p = tmp_path / "c.map"
    p.write_bytes(MAI.replace("\n", "\r\n").encode() + b"\r\n\r\n")
    assert read_map(p).blocked.sum() == 3
    p.write_text("\n0,0,0\n\n0 1 0\n0\t0 0\n\n")
    assert read_map(p).blocked.tolist() == [[False] * 3, [False, True, False], [False] * 3]
