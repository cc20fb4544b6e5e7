"""Kill -9 at up to 20 points of each study's finishing phase, then ``evomotion resume``: a
table of the points tried and how many resumed to artifacts identical to an uninterrupted
run's (issue 31). The same procedure as ``tests/studies/test_finish_kill.py`` (its helpers
are reused), with the finishing phase's write events and time measured.

    python benchmarks/finish_kill.py [--only STUDY] [--points 20]
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "studies"))

from test_finish_kill import (  # noqa: E402
    CASES,
    _config,
    _files,
    _finished,
    _preload,
)

from evomotion.run.faults import in_child, kill_in_finishing  # noqa: E402
from evomotion.run.runner import run_study  # noqa: E402

NEVER = 1 << 60


def measure(case: str, points: int, tmp: Path) -> dict:
    s, cfg = _config(case)
    _preload(s)

    def run(out: Path, point: int | None = None, count: Path | None = None, resume=False,
            after_s: float | None = None):
        def go():
            if point is not None or count is not None or after_s is not None:
                kill_in_finishing(point if point is not None else NEVER, count, after_s)
            return run_study(s, cfg, out, quiet=True, resume=resume).exit_code
        return in_child(go)

    ref, template = tmp / "ref", tmp / "template"
    code = run(ref)
    assert run(template, point=0) == -9
    probe, counted = tmp / "probe", tmp / "count"
    shutil.copytree(template, probe, symlinks=True)
    assert run(probe, count=counted, resume=True) == code
    events, finish_s = (json.loads(counted.read_text())[k] for k in ("events", "seconds"))
    want = _files(ref)
    chosen: list = sorted({1 + round(i * (events - 1) / (points - 1)) for i in range(points)})
    timed = points - len(chosen)  # fewer write events than points: kills at times between
    chosen += [finish_s * (i + 1) / (timed + 1) for i in range(timed)]
    same = done_before = 0
    for i, k in enumerate(chosen):
        d = tmp / f"k{i}"
        shutil.copytree(template, d, symlinks=True)
        if isinstance(k, float):
            run(d, resume=True, after_s=k)
        else:
            assert run(d, point=k, resume=True) == -9
        if _finished(d):
            done_before += 1
        elif run(d, resume=True) != code:
            continue
        same += _files(d) == want
    return {"case": case, "files": len(want), "events": events, "points": len(chosen),
            "timed": timed,
            "identical": same, "finished_before_kill": done_before,
            "finishing_s": finish_s}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default=None)
    ap.add_argument("--points", type=int, default=20)
    a = ap.parse_args()
    print("| study | files compared | write events in finishing | kill points (at events + "
          "at times) | identical after resume | finishing phase s |")
    print("|---|---|---|---|---|---|")
    for case in CASES:
        if a.only and a.only not in case:
            continue
        with tempfile.TemporaryDirectory() as tmp:
            r = measure(case, a.points, Path(tmp))
        print(f"| {r['case']} | {r['files']} | {r['events']} | "
              f"{r['points']} ({r['points'] - r['timed']} + {r['timed']}) | "
              f"{r['identical']} / {r['points']} | {r['finishing_s']:.1f} |", flush=True)


if __name__ == "__main__":
    main()
