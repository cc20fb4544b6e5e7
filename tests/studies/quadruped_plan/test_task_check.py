"""``quadruped-plan check`` verifies a plan against its task (the world file, the run's
configuration), not against the fields of the file it checks: a walk that stopped short
fails however its ``goal`` is edited."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.studies import get_study

TINY = Path(__file__).parent / "data" / "tiny.world"
SETS = [f"problem.world='{TINY}'", "algorithm.name=receding", "run.seed=4",
        "problem.gif_max_frames=2"]


def _run(out: Path, *extra: str) -> Path:
    s = get_study("quadruped-plan")
    run_study(s, resolve_config(s, None, [*SETS, *extra]), out, quiet=True)
    return out


@pytest.fixture(scope="module")
def short(tmp_path_factory) -> Path:
    """A walk stopped after 30 transitions, far from the goal."""
    out = _run(tmp_path_factory.mktemp("short"), "algorithm.max_transitions=30")
    doc = json.loads((out / "mission.json").read_text())
    assert doc["search"]["outcome"] == "failed: 30 transitions"
    return out


@pytest.fixture(scope="module")
def reached(tmp_path_factory) -> Path:
    out = _run(tmp_path_factory.mktemp("reached"))
    assert json.loads((out / "mission.json").read_text())["search"]["outcome"] == "reached"
    return out


def _check(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "evomotion.cli", "quadruped-plan", "check",
                           *args], capture_output=True, text=True, timeout=120)


def _edited(src: Path, dst: Path, edit) -> Path:
    """A copy of the run folder with mission.json edited."""
    shutil.copytree(src, dst)
    p = dst / "mission.json"
    doc = json.loads(p.read_text())
    edit(doc)
    p.write_text(json.dumps(doc))
    return dst


def _fails(r: subprocess.CompletedProcess, words: str) -> None:
    lines = r.stdout.strip().splitlines()
    assert r.returncode == 1 and "Traceback" not in r.stderr, (r.stdout, r.stderr)
    assert len(lines) == 1 and words in lines[0], r.stdout


def _goal_at_the_end(doc: dict) -> None:
    end = doc["states"][-1]["body"][:2]
    doc["goal"] = end
    for h in doc.get("goal_history", []):
        h["goal"] = end


def test_a_walk_that_stopped_short_fails_with_its_goal_edited(short, tmp_path):
    _fails(_check(str(short)), "from the goal")
    forged = _edited(short, tmp_path / "forged", _goal_at_the_end)
    _fails(_check(str(forged)), "goal_history[0]: the walk's first goal is not the goal")
    _fails(_check(str(forged / "mission.json")), "is not the goal")

    def first_only(doc: dict) -> None:  # one consistent goal: still not the world's
        _goal_at_the_end(doc)
        doc.pop("goal_history")

    _fails(_check(str(_edited(short, tmp_path / "single", first_only))),
           "is not the goal of the world")


def test_a_reached_walk_passes_and_edits_of_its_task_fail(reached, tmp_path):
    r = _check(str(reached))
    assert r.returncode == 0 and f"against the world {TINY}" in r.stdout, r.stdout + r.stderr

    def far_move(doc: dict) -> None:  # the goal "moved" 5 units: more than 2
        g = [doc["goal"][0] + 5.0, doc["goal"][1]]
        doc["goal"] = g
        doc["goal_history"] = [doc["goal_history"][0], {"goal": g, "from": 3}]

    _fails(_check(str(_edited(reached, tmp_path / "far", far_move))), "a goal moves at most 2")

    def no_obstacles(doc: dict) -> None:
        doc["world"]["polygons"] = [p for p in doc["world"]["polygons"]
                                    if p["kind"] != "obstacle"]

    _fails(_check(str(_edited(reached, tmp_path / "open", no_obstacles))),
           "world.polygons: the plan's obstacles")

    def loose(doc: dict) -> None:
        doc["goal_tolerance"] = 100.0

    _fails(_check(str(_edited(reached, tmp_path / "loose", loose))), "goal_tolerance: 100")

    def elsewhere(doc: dict) -> None:
        for s in doc["states"]:
            s["body"][1] += 1.0
            for f in s["feet"]:
                f[1] += 1.0

    _fails(_check(str(_edited(reached, tmp_path / "moved", elsewhere))),
           "does not start at the start")


def test_the_world_can_be_named_and_a_foreign_world_fails(reached, tmp_path):
    lone = tmp_path / "lone.json"
    shutil.copy(reached / "mission.json", lone)  # no run folder beside it
    r = _check(str(lone))
    assert r.returncode == 2 and "not a bundled world; name its file with --world" in r.stderr
    r = _check(str(lone), "--world", str(TINY))
    assert r.returncode == 0 and "ok" in r.stdout, r.stdout + r.stderr
    _fails(_check(str(lone), "--world", "gaps"), "gaps.world (26, 0)")
