"""Kill -9 while a run writes its final artifacts, for every study: ``evomotion resume``
completes them, identical to an uninterrupted run's (no exemptions).

A run killed while finishing used to leave its artifacts missing or different (the
quadruped's mission.json, the repertoire's archive.npz and index.json) and ``resume`` refused
("the run already finished"). Here each study's smoke run is killed (SIGKILL, in a forked
child) at :data:`POINTS` points of its finishing phase, spread evenly over its write events
(before and after each file's bytes are written: every write goes through
:mod:`evomotion.outfile`) from the first to the last; after each kill it is resumed to the end
and every file it holds is compared with an uninterrupted run's.
"""

from __future__ import annotations

import hashlib
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from evomotion.run.config import resolve_config
from evomotion.run.faults import in_child, kill_in_finishing
from evomotion.run.runner import run_study
from evomotion.studies import STUDIES, get_study

#: 8 since 2026-12-07 (20 before: this file took a third of CI's 30 minutes on a slow VM)
POINTS = 8
#: columns and keys that measure time, not results
TIMED_COLUMNS = {"wall_s", "evals_per_s", "plan_ms"}
TIMED_KEYS = {"time_to_solution_s", "wall_s", "elapsed_s", "plan_ms", "plan_ms_max",
              "plan_ms_median", "expansions_per_s", "evals_per_s"}
#: what the run loop keeps for itself (differs by design between two runs of one seed)
SKIP = {"log.txt", "run.lock", "checkpoints"}
CASES = sorted(STUDIES) + ["quadruped-plan:receding"]
#: the receding walker needs a world; a small one of the quadruped tests
TINY_WORLD = Path(__file__).parent / "quadruped_plan" / "data" / "tiny.world"
METHOD_SETS = {"receding": [f"problem.world='{TINY_WORLD}'", "problem.gif_max_frames=4"]}


def _config(case: str):
    name, _, method = case.partition(":")
    s = get_study(name)
    sets = [*(s.smoke if not method else METHOD_SETS[method]), "run.generations=4",
            "run.checkpoint_every=2", "run.wall_seconds=0", "run.seed=5", "run.videos=false"]
    if method:
        sets.append(f"algorithm.name={method}")
    return s, resolve_config(s, None, sets)


def _files(d: Path) -> dict[str, object]:
    out: dict[str, object] = {}
    for p in sorted(d.rglob("*")):
        rel = p.relative_to(d)
        if rel.parts[0] in SKIP or not p.is_file():
            continue
        if p.name == "stats.csv":
            rows = [ln.split(",") for ln in p.read_text().splitlines()]
            keep = [i for i, c in enumerate(rows[0]) if c not in TIMED_COLUMNS]
            out[str(rel)] = [[r[i] for i in keep] for r in rows]
        elif p.suffix == ".json":
            out[str(rel)] = _untimed(json.loads(p.read_text()))
        else:
            out[str(rel)] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def _untimed(doc: object) -> object:
    if isinstance(doc, dict):
        return {k: _untimed(v) for k, v in doc.items() if k not in TIMED_KEYS}
    if isinstance(doc, list):
        return [_untimed(v) for v in doc]
    return doc


#: runs :func:`check_case` of this file in a fresh interpreter
RUNNER = ("import importlib.util, pathlib, sys\n"
          "spec = importlib.util.spec_from_file_location('finish_kill', sys.argv[1])\n"
          "m = importlib.util.module_from_spec(spec)\n"
          "spec.loader.exec_module(m)\n"
          "m.check_case(sys.argv[2], pathlib.Path(sys.argv[3]))\n")


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES)
def test_kill_9_while_finishing_then_resume_completes_identically(case, tmp_path):
    """Each case in a fresh Python process: the kills fork it, and a fork of a process that
    other tests left with threads (MuJoCo's rollout pool, a test runner's workers) can hang."""
    r = subprocess.run([sys.executable, "-c", RUNNER, __file__, case, str(tmp_path)],
                       capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]


def check_case(case: str, tmp_path: Path) -> None:
    """The test of one case (see the module): raises AssertionError on a difference."""
    s, cfg = _config(case)

    def run(out: Path, point: int | None = None, count: Path | None = None, resume=False,
            after_s: float | None = None):
        def go():
            if point is not None or count is not None or after_s is not None:
                kill_in_finishing(point if point is not None else 1 << 60, count, after_s)
            return run_study(s, cfg, out, quiet=True, resume=resume).exit_code
        return in_child(go)

    _preload(s)
    ref, template = tmp_path / "uninterrupted", tmp_path / "template"
    code = run(ref)
    assert code in (0, 1, 3), f"the uninterrupted run exited {code}"
    assert run(template, point=0) == -9
    assert _finished(template) is False
    counted = tmp_path / "count"
    probe = tmp_path / "probe"
    shutil.copytree(template, probe, symlinks=True)
    assert run(probe, count=counted, resume=True) == code
    events, finish_s = (json.loads(counted.read_text())[k] for k in ("events", "seconds"))
    assert _files(probe) == _files(ref)
    points: list = sorted({1 + round(i * (events - 1) / (POINTS - 1)) for i in range(POINTS)})
    # a phase with fewer write events than POINTS: the rest are kills at times into it
    extra = POINTS - len(points)
    points += [("s", finish_s * (i + 1) / (extra + 1)) for i in range(extra)]
    assert len(points) == POINTS
    for k in points:
        d = tmp_path / f"k{k}"
        shutil.copytree(template, d, symlinks=True)
        if isinstance(k, tuple):  # a time into the phase: it may end before the kill
            assert run(d, resume=True, after_s=k[1]) in (-9, code)
        else:
            assert run(d, point=k, resume=True) == -9, f"point {k} of {events} not reached"
        if _finished(d):  # killed after the run recorded that it is done
            assert isinstance(k, tuple) or k >= events - 3, f"point {k}: finished too early"
        else:
            assert run(d, resume=True) == code, f"the resume after a kill at point {k} failed"
            assert _finished(d)
        assert _files(d) == _files(ref), f"artifacts differ after a kill at point {k}"


def _preload(study) -> None:
    """Import in this process what every child would import (each point costs a fork, not
    a second of imports); no problem is built here (no threads before a fork)."""
    import importlib

    import evomotion.run.plots  # noqa: F401 - matplotlib

    for hook in (study.on_checkpoint, study.finalize, study.best_record):
        mod = getattr(hook, "module", None)
        if isinstance(mod, str):
            importlib.import_module(mod)
    importlib.import_module(study.make_problem.__module__)


def _finished(d: Path) -> bool:
    ck = json.loads((d / "checkpoints" / "latest.json").read_text())["checkpoint"]
    return json.loads((d / "checkpoints" / ck).read_text())["counters"]["finished"]
