"""World files a hostile user can write: huge bounds, too many vertices, polygons too costly to
carve, FIFOs, a start or goal where the robot cannot stand. Each is one line naming the file
and the line, before any grid is allocated or any search runs."""

from __future__ import annotations

import math
import os
import re
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from evomotion.errors import FileFormatError, InputError
from evomotion.studies.quadruped_plan.missions.mission import Mission
from evomotion.studies.quadruped_plan.plans.planner import QuadrupedPlanConfig, make_problem
from evomotion.studies.quadruped_plan.rules.model import QuadrupedModel
from evomotion.studies.quadruped_plan.worlds.terrain import Terrain
from evomotion.studies.quadruped_plan.worlds.world import load_world, read_world

MODEL = QuadrupedModel()
HEAD = "start 0 0 90\ngoal 10 0\n"


def _world(tmp_path: Path, text: str, name: str = "w.world") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def _one_line(e: pytest.ExceptionInfo, path: Path, line: int | None) -> str:
    msg = str(e.value)
    where = f"{path}:{line}: " if line is not None else f"{path}: "
    assert msg.startswith(where), msg
    assert "\n" not in msg and len(msg) < len(str(path)) + 260, msg
    return msg


@pytest.mark.parametrize("bounds", ["-1e4 -1e4 1e4 1e4", "-1000 -1000 1000 1000",
                                    "-1e4 -5 1e4 5"])
def test_huge_bounds_are_refused_on_their_line_before_any_grid(tmp_path, bounds):
    """298 GiB and 6.7 GiB allocations used to end in numpy's _ArrayMemoryError."""
    p = _world(tmp_path, f"bounds {bounds}\n{HEAD}")
    with pytest.raises(FileFormatError) as e:
        read_world(p)
    assert "nodes" in _one_line(e, p, 1)
    with pytest.raises(FileFormatError):  # the same through a configuration
        make_problem(QuadrupedPlanConfig(world=str(p)))


def test_bounds_from_far_apart_points_are_refused_too(tmp_path):
    p = _world(tmp_path, "start 0 0 90\ngoal 9000 9000\n")
    with pytest.raises(FileFormatError) as e:
        read_world(p)
    assert "from the points named" in _one_line(e, p, None)


def test_the_largest_accepted_world_builds_its_grids_in_bounded_memory(tmp_path):
    p = _world(tmp_path, "bounds 0 0 140 140\nstart 5 5 90\ngoal 130 130\n"
                         "obstacle 60 60  70 60  70 70  60 70\n")
    from evomotion.studies.quadruped_plan.worlds.world import MAX_GRID_NODES, grid_nodes

    w = read_world(p)
    nx, ny = grid_nodes(w.bounds)
    assert nx * ny <= MAX_GRID_NODES
    t = Terrain(w, MODEL)
    assert t.body_sdf.shape == (nx, ny) and t.body_sdf.nbytes < 20e6


def test_a_terrain_refuses_a_grid_too_fine_before_allocating(tmp_path):
    w = read_world(_world(tmp_path, f"bounds -50 -50 50 50\n{HEAD}"))
    with pytest.raises(InputError, match="grid nodes"):
        Terrain(w, MODEL, grid=0.001)


def test_vertex_counts_and_carving_work_are_bounded(tmp_path):
    ring = lambda n, r, c: "  ".join(  # noqa: E731
        f"{c + r * math.cos(a):.5f} {c + r * math.sin(a):.5f}"
        for a in np.linspace(0, 2 * math.pi, n, endpoint=False))
    many = "".join(f"nostep {ring(999, 0.3, 50 + (k % 40))}\n" for k in range(21))
    p = _world(tmp_path, f"bounds 0 0 100 100\nstart 5 5 90\ngoal 95 95\n{many}")
    with pytest.raises(FileFormatError) as e:
        read_world(p)
    assert "at most 20,000" in _one_line(e, p, 4 + 20_000 // 999)
    big = _world(tmp_path, f"bounds 0 0 100 100\nstart 5 5 90\ngoal 95 95\n"
                           f"obstacle {ring(400, 30, 50)}\n", "big.world")
    t0 = time.perf_counter()
    with pytest.raises(FileFormatError) as e:
        read_world(big)
    assert "node-edge distances" in _one_line(e, big, 4)
    assert time.perf_counter() - t0 < 5


def _fifo(tmp_path: Path) -> Path:
    p = tmp_path / "pipe.world"
    os.mkfifo(p)
    return p


def _no_block(fn, *args):
    """``fn(*args)``'s exception, failing the test if it blocks for 10 s."""
    out: dict = {}

    def go():
        try:
            fn(*args)
        except Exception as e:  # noqa: BLE001
            out["e"] = e

    th = threading.Thread(target=go, daemon=True)
    th.start()
    th.join(10)
    assert not th.is_alive(), f"{fn.__name__} blocked on a FIFO"
    return out.get("e")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_a_fifo_world_is_refused_without_blocking_on_every_path(tmp_path):
    p = _fifo(tmp_path)
    for fn, arg in ((read_world, p), (load_world, str(p)),
                    (make_problem, QuadrupedPlanConfig(world=str(p)))):
        e = _no_block(fn, arg)
        assert isinstance(e, FileFormatError) and "FIFO" in str(e), (fn, e)
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "quadruped-plan",
                        "--set", f"problem.world='{p}'", "--set", "algorithm.name=receding",
                        "--out", str(tmp_path / "run"), "-q"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "FIFO" in r.stderr and "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr


@pytest.mark.parametrize(("goal", "words"), [
    ("5 0", "inside an obstacle (line 3)"),  # inside the rock
    ("5 -1.8", "cannot stand"),  # 0.8 from it: no room for the body
])
def test_a_goal_where_the_robot_cannot_stand_is_refused_before_searching(tmp_path, goal,
                                                                         words):
    """It used to search to the 200,000-expansion budget (26 s)."""
    p = _world(tmp_path, f"start 0 0 90\ngoal {goal}\nobstacle 4 -1  6 -1  6 1  4 1\n"
                         "bounds -8 -8 16 8\n")
    t0 = time.perf_counter()
    with pytest.raises(FileFormatError) as e:
        make_problem(QuadrupedPlanConfig(world=str(p)))
    assert words in _one_line(e, p, 2)
    with pytest.raises(FileFormatError, match=re.escape(words)):  # the receding walker too
        Mission(load_world(str(p)), MODEL).start()
    assert time.perf_counter() - t0 < 5


def test_a_start_inside_a_hidden_obstacle_or_a_goal_off_the_bounds_edge(tmp_path):
    p = _world(tmp_path, "start 0 0 90\ngoal 10 0\nhidden -1 -1  1 -1  1 1  -1 1\n")
    with pytest.raises(FileFormatError) as e:
        read_world(p)
    assert "inside a hidden obstacle (line 3)" in _one_line(e, p, 1)
    q = _world(tmp_path, "bounds -6 -6 10.5 6\nstart 0 0 90\ngoal 10 0\n", "edge.world")
    with pytest.raises(FileFormatError) as e:
        make_problem(QuadrupedPlanConfig(world=str(q)))
    assert "does not fit inside the bounds" in _one_line(e, q, 3)


def test_the_cli_refuses_a_goal_inside_an_obstacle_in_one_line(tmp_path):
    p = _world(tmp_path, "start 0 0 90\ngoal 5 0\nobstacle 4 -1  6 -1  6 1  4 1\n")
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "quadruped-plan",
                        "--set", f"problem.world='{p}'", "--out", str(tmp_path / "run"), "-q"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert r.stderr.strip().startswith(f"error: {p}:2: goal:")
    assert time.perf_counter() - t0 < 30


@pytest.mark.parametrize("worlds", ["", ",,"])
def test_missions_without_a_world_is_one_line(tmp_path, worlds):
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "quadruped-plan", "missions",
                        "--seeds", "1", "--worlds", worlds], capture_output=True, text=True,
                       timeout=120, cwd=tmp_path)
    assert r.returncode == 2 and r.stdout == "", r.stdout
    assert r.stderr.strip() == f"error: --worlds: expected one or more comma-separated " \
                               f"worlds, got {worlds!r}"


@pytest.mark.parametrize("option, value, message", [
    ("--astar-seconds", "0", "--astar-seconds: expected a value in (0.0, 3600.0]"),
    ("--astar-seconds", "inf", "--astar-seconds: expected a finite number"),
    ("--max-expansions", "0", "--max-expansions: expected a value in [1, 1000000000]"),
    ("--astar-pos-grid", "nan", "--astar-pos-grid: expected a finite number"),
])
def test_study_budgets_out_of_range_are_one_line(tmp_path, option, value, message):
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "quadruped-plan", "study",
                        option, value], capture_output=True, text=True, timeout=120,
                       cwd=tmp_path)
    assert r.returncode == 2 and r.stdout == "", r.stdout
    assert r.stderr.strip().startswith(f"error: {message}"), r.stderr


NUMBER = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=64),
                   st.integers(-10**6, 10**6), st.sampled_from([1e300, -1e300, 1e4, 1e-300]),
                   st.floats(-30, 30))
SMALL = st.floats(-20, 20, allow_nan=False)


@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
@given(SMALL, SMALL, SMALL, SMALL,
       st.lists(st.one_of(
           st.tuples(st.sampled_from(["bounds", "view", "obstacle", "nostep", "hidden", "name",
                                      "goal"]), st.lists(NUMBER, min_size=0, max_size=9)),
           st.tuples(st.sampled_from(["obstacle", "nostep", "hidden"]),
                     st.tuples(NUMBER, NUMBER, st.floats(0.01, 50))
                     .map(lambda t: [t[0], t[1], t[0] + t[2], t[1], t[0] + t[2], t[1] + t[2]])),
           st.tuples(st.just("bounds"), st.tuples(NUMBER, NUMBER, NUMBER, NUMBER)
                     .map(lambda t: [-abs(t[0]), -abs(t[1]), abs(t[2]), abs(t[3])]))),
           max_size=6))
def test_fuzz_world_statements(tmp_path_factory, sx, sy, gx, gy, statements):
    """A start, a goal and any mix of statements and numbers: a world within the limits that
    a run can use or refuse in one line, or one line from the reader."""
    text = f"start {sx!r} {sy!r} 90\ngoal {gx!r} {gy!r}\n" + "".join(
        f"{k} {' '.join(repr(v) for v in vals)}\n" for k, vals in statements)
    p = tmp_path_factory.mktemp("fuzz") / "f.world"
    p.write_text(text)
    try:
        w = read_world(p)
    except FileFormatError as e:
        assert str(e).startswith(f"{p}") and "\n" not in str(e)
        event("refused by the reader")
        return
    event("read")
    x0, y0, x1, y1 = w.bounds
    assert (math.ceil((x1 - x0) / 0.1) + 1) * (math.ceil((y1 - y0) / 0.1) + 1) <= 2_000_000
    assert all(np.isfinite(q.points).all() for q in w.polygons)
    assert np.isfinite([*w.bounds, *w.start, *w.goal, w.view, w.goal_tolerance]).all()
    try:  # what a run does next: one line, or a problem to search
        make_problem(QuadrupedPlanConfig(world=str(p)))
    except FileFormatError as e:
        assert str(e).startswith(f"{p}") and "\n" not in str(e)
