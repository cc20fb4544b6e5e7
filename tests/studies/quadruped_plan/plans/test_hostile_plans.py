"""Plans a hostile user can hand to ``quadruped-plan simulate`` / ``check``, and output paths
that cannot be written: one line each, before the simulation or the walks run."""

from __future__ import annotations

import copy
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from evomotion import outfile
from evomotion.errors import FileFormatError, InputError
from evomotion.studies.quadruped_plan.plans.checker import PlanViolationError, check_plan
from evomotion.studies.quadruped_plan.plans.plan import plan_document, read_plan, write_plan
from evomotion.studies.quadruped_plan.plans.planner import QuadrupedPlanConfig, make_problem, solve

SHORT = QuadrupedPlanConfig(start_phi=0.0, goal_x=0.0, goal_y=-3.0, rule_set="B",
                            gif_max_frames=4)


@pytest.fixture(scope="module")
def doc() -> dict:
    p = make_problem(SHORT)
    res = solve(SHORT, None, p)
    assert res.found
    d = plan_document(p.model, res.states, res.rules, p.goal, SHORT.goal_tolerance,
                      SHORT.sense, SHORT.rule_set, None, {"expansions": res.expansions})
    return json.loads(json.dumps(d))


def _write(tmp_path: Path, d: dict, name: str = "plan.json") -> Path:
    p = tmp_path / name
    p.write_text(json.dumps(d))
    return p


def _limited() -> None:  # pragma: no cover - in the child
    """At most 3 GiB of address space: an allocation of many GiB fails at once."""
    resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))


def _cli(*args: str, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "evomotion.cli", *args], capture_output=True,
                          text=True, timeout=timeout, preexec_fn=_limited)


def _one_error_line(r: subprocess.CompletedProcess, start: str) -> str:
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr[-2000:]
    assert len(lines) == 1 and lines[0].startswith(f"error: {start}"), r.stderr
    return lines[0]


def test_simulate_refuses_an_enormous_model_in_one_line(doc, tmp_path):
    """It used to end in QuadrupedSpec's ValueError traceback."""
    big = copy.deepcopy(doc)
    big["model"]["a"] = 1e5
    p = _write(tmp_path, big)
    line = _one_error_line(_cli("quadruped-plan", "simulate", str(p)), str(p))
    assert "model" in line and "cannot be built" in line


def test_simulate_refuses_a_plan_that_would_take_days_to_execute(doc, tmp_path):
    """A body move of 90,000 units (9 km at 5 cm/s): refused from the plan's numbers,
    before a timeline of 10^8 steps is allocated."""
    far = copy.deepcopy(doc)
    last = far["states"][-1]
    last["body"][0] += 9e4
    for f in last["feet"]:
        f[0] += 9e4
    p = _write(tmp_path, far)
    t0 = time.perf_counter()
    line = _one_error_line(_cli("quadruped-plan", "simulate", str(p)), str(p))
    assert "simulated seconds" in line and time.perf_counter() - t0 < 60


@pytest.mark.parametrize(("edit", "words"), [
    (lambda d: d["search"].__setitem__("x", float("nan")), "search.x: expected a finite"),
    (lambda d: d["search"].__setitem__("n", 10**30), "search.n: expected an integer"),
    (lambda d: d.__setitem__("states", d["states"] * (10_001 // len(d["states"]) + 1)),
     "states: expected a list of 1 to 10,000"),
    (lambda d: d.__setitem__("world", {"bounds": [0, 0, 9, 9], "polygons": [
        {"kind": "nostep", "points": [[0, 0], [1, 0], [1, 1]] * 300}] * 30}),
     "vertices in all"),
    (lambda d: d.__setitem__("goal_history", [{"goal": [0, "x"], "from": 0}]),
     "goal_history[0].goal[1]"),
])
def test_read_plan_bounds_sizes_and_numbers(doc, tmp_path, edit, words):
    d = copy.deepcopy(doc)
    edit(d)
    p = tmp_path / "p.json"
    p.write_text(json.dumps(d, allow_nan=True))
    with pytest.raises(FileFormatError) as e:
        read_plan(p)
    assert str(e.value).startswith(f"{p}: ") and words in str(e.value), str(e.value)
    assert "\n" not in str(e.value)


def test_read_plan_bounds_nesting(tmp_path):
    p = tmp_path / "deep.json"
    p.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(FileFormatError, match="nested less deeply"):
        read_plan(p)


HOSTILE = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(),
                    st.sampled_from([1e300, -1e300, 1e6, 1e7, 0, -1, True, None, "x", []]))


@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.data())
def test_fuzz_plan_numbers(doc, tmp_path_factory, data):
    """Any number of the plan replaced by a hostile value: read_plan refuses it in one line,
    or check and the simulation's own checks give a verdict, never a crash."""
    from evomotion.studies.quadruped_plan.plans.simulate import check_document
    from evomotion.studies.quadruped_plan.task_check import Task, apply_task

    d = copy.deepcopy(doc)
    for _ in range(data.draw(st.integers(1, 3))):
        where = data.draw(st.sampled_from(["model", "goal", "state", "foot"]))
        value = data.draw(HOSTILE)
        if where == "model":
            d["model"][data.draw(st.sampled_from(sorted(d["model"])))] = value
        elif where == "goal":
            d["goal"][data.draw(st.integers(0, 1))] = value
        else:
            s = d["states"][data.draw(st.integers(0, len(d["states"]) - 1))]
            if where == "state":
                s["body"][data.draw(st.integers(0, 2))] = value
            else:
                s["feet"][data.draw(st.integers(0, 3))][data.draw(st.integers(0, 1))] = value
    p = tmp_path_factory.mktemp("fuzz") / "plan.json"
    p.write_text(json.dumps(d, allow_nan=True))
    try:
        back = read_plan(p)
    except FileFormatError as e:
        assert "\n" not in str(e)
        return
    try:
        check_plan(back)
    except PlanViolationError as e:
        assert "\n" not in str(e)
    task = Task("configuration", (0.0, 0.0, 0.0), (0.0, -3.0), 0.25)
    try:
        check_plan(apply_task(back, task))
    except PlanViolationError as e:
        assert "\n" not in str(e)
    try:
        check_document(back, p)
    except InputError as e:
        assert str(e).startswith(str(p)) and "\n" not in str(e)


def test_video_into_a_missing_folder_is_refused_before_the_simulation(doc, tmp_path,
                                                                      monkeypatch):
    """It used to fail with FileNotFoundError after the whole simulation."""
    from evomotion.studies.quadruped_plan.plans import simulate

    p = _write(tmp_path, doc)
    target = tmp_path / "no" / "walk.mp4"
    line = _one_error_line(_cli("quadruped-plan", "simulate", str(p), "--video",
                                str(target)), str(target))
    assert "does not exist" in line and not target.parent.exists()

    def no_simulation(*a, **kw):
        raise AssertionError("simulated before the video path was checked")

    monkeypatch.setattr(simulate, "execute_plan", no_simulation)
    with pytest.raises(outfile.WriteError, match="does not exist"):
        simulate.simulate_document(doc, target)


def test_missions_json_into_a_missing_folder_is_refused_before_the_walks(tmp_path):
    target = tmp_path / "no" / "figures.json"
    t0 = time.perf_counter()
    r = _cli("quadruped-plan", "missions", "--seeds", "1", "--worlds", "gaps", "--json",
             str(target))
    line = _one_error_line(r, str(target))
    assert "does not exist" in line and time.perf_counter() - t0 < 30
    assert not r.stdout.strip(), "walks ran before the output path was checked"


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_plans_are_written_by_the_atomic_writer(doc, tmp_path):
    seen: list[Path] = []

    def hook(event: str, path: Path) -> None:
        seen.append(Path(path))

    outfile.WRITE_HOOKS.append(hook)
    try:
        write_plan(tmp_path / "plan.json", doc)
        fifo = tmp_path / "fifo.json"
        os.mkfifo(fifo)
        with pytest.raises(outfile.WriteError, match="FIFO"):
            write_plan(fifo, doc)
    finally:
        outfile.WRITE_HOOKS.remove(hook)
    assert tmp_path / "plan.json" in seen
    assert read_plan(tmp_path / "plan.json") == doc
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fifo.json", "plan.json"]


def test_a_run_writes_its_plan_and_pictures_through_the_atomic_writer(tmp_path):
    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study
    from evomotion.studies.quadruped_plan.study import STUDY

    seen: list[str] = []

    def hook(event: str, path: Path) -> None:
        if event == "written":
            seen.append(Path(path).name)

    cfg = resolve_config(STUDY, overrides=[*STUDY.smoke, "problem.goal_y=-3.0"])
    outfile.WRITE_HOOKS.append(hook)
    try:
        assert run_study(STUDY, cfg, tmp_path / "run", quiet=True).exit_code == 0
    finally:
        outfile.WRITE_HOOKS.remove(hook)
    assert {"plan.json", "plan.png", "plan.gif"} <= set(seen), seen
    assert not [p for p in (tmp_path / "run").iterdir() if ".tmp" in p.name]
