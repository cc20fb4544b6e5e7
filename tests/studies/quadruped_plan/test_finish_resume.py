"""The receding walker's final artifacts (mission.json, plan.png, plan.gif) are a function of
the run state alone: ``evomotion resume`` of a run stopped while writing them (killed, or
with them deleted) writes the same bytes."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.studies import get_study

TINY = Path(__file__).parent / "data" / "tiny.world"
SETS = [f"problem.world='{TINY}'", "algorithm.name=receding", "run.seed=4",
        "run.checkpoint_every=2", "problem.gif_max_frames=3"]
FINAL = ("mission.json", "plan.png", "plan.gif", "best.json")
TIMED = {"plan_ms_median", "plan_ms_max", "expansions_per_s"}


def _run(out: Path, resume: bool = False) -> int:
    s = get_study("quadruped-plan")
    return run_study(s, resolve_config(s, None, SETS), out, quiet=True,
                     resume=resume).exit_code


def _latest(run: Path) -> Path:
    ck = run / "checkpoints"
    return ck / json.loads((ck / "latest.json").read_text())["checkpoint"]


@pytest.fixture(scope="module")
def done(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("done")
    assert _run(out) == 0
    return out


def test_deleted_final_artifacts_are_rewritten_byte_for_byte(done, tmp_path):
    again = tmp_path / "again"
    shutil.copytree(done, again)
    for name in FINAL:
        (again / name).unlink()
    ck = _latest(again)
    meta = json.loads(ck.read_text())
    assert meta["counters"]["finished"] is True
    meta["counters"]["finished"] = False  # as if stopped while writing them
    ck.write_text(json.dumps(meta))
    assert _run(again, resume=True) == 0
    for name in FINAL:
        assert (again / name).read_bytes() == (done / name).read_bytes(), name
    assert "to write the final artifacts" in (again / "log.txt").read_text()


def _untimed(doc: object) -> object:
    if isinstance(doc, dict):
        return {k: _untimed(v) for k, v in doc.items() if k not in TIMED}
    if isinstance(doc, list):
        return [_untimed(v) for v in doc]
    return doc


#: a run killed (SIGKILL) by its own write hook once ``at`` is written, in a fresh interpreter
#: (a fork of the test process, which other tests left with threads, can hang)
KILLED = """
import os, signal, sys
from pathlib import Path
from evomotion import outfile
from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.studies import get_study
out, at, sets = Path(sys.argv[1]), sys.argv[2], sys.argv[3:]
def hook(event, path):
    if event == "written" and Path(path).name == at:
        os.kill(os.getpid(), signal.SIGKILL)
outfile.WRITE_HOOKS.append(hook)
s = get_study("quadruped-plan")
sys.exit(run_study(s, resolve_config(s, None, sets), out, quiet=True).exit_code)
"""


@pytest.mark.parametrize("at", ["mission.json", "plan.gif"])
def test_killed_while_writing_then_resumed_matches_an_uninterrupted_run(done, tmp_path, at):
    out = tmp_path / "killed"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    r = subprocess.run([sys.executable, "-c", KILLED, str(out), at, *SETS], env=env,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == -signal.SIGKILL, r.stderr
    assert json.loads(_latest(out).read_text())["counters"]["finished"] is False
    if at == "mission.json":
        assert not (out / "mission.json").exists()  # nothing half-written took its place
    assert _run(out, resume=True) == 0
    assert not [p.name for p in out.iterdir() if ".tmp" in p.name]
    mine, ref = (json.loads((d / "mission.json").read_text()) for d in (out, done))
    assert _untimed(mine) == _untimed(ref)
    for name in ("plan.png", "plan.gif"):
        assert (out / name).read_bytes() == (done / name).read_bytes(), name
