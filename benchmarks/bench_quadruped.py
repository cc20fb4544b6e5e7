"""Benchmark: quadruped-plan search speed (paper 003).

Prints expansions per second of the paper's best-first search and the time to run the whole
12-configuration table (2 starts x rule sets A, B x functions 1-3). Both are given in CPU
seconds of this process (robust on a shared machine) and in wall seconds, with the load
average. Targets: >= 50,000 expansions/s; the table in < 10 s.

``--baseline REV`` also times the package as committed at git revision REV (exported to a
temporary folder and run in a child process), alternating with the current code in the same
run, prints the CPU-time ratio, and checks that both give the same expansions and plans.

    python benchmarks/bench_quadruped.py [--repeat N] [--baseline REV]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tarfile
import tempfile
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def table_once() -> tuple[int, float, float, dict[str, list]]:
    """Run the 12 configurations once: (expansions, CPU s, wall s, per-configuration
    [expansions, CPU s, rules of the plan])."""
    try:
        from evomotion.studies.quadruped_plan.plans.experiment import STARTS
        from evomotion.studies.quadruped_plan.plans.planner import (
            QuadrupedPlanConfig,
            make_problem,
            solve,
        )
    except ImportError:  # a baseline before issue 32: flat modules
        from evomotion.studies.quadruped_plan.experiment import STARTS  # type: ignore
        from evomotion.studies.quadruped_plan.planner import (  # type: ignore
            QuadrupedPlanConfig,
            make_problem,
            solve,
        )

    try:
        from evomotion.studies.quadruped_plan.plans.search_config import SearchConfig
    except ImportError:  # a baseline before issue 32: the search settings in [problem]
        SearchConfig = None  # noqa: N806
    expansions, cpu, wall, per = 0, 0.0, 0.0, {}
    for function in (1, 2, 3):
        for rule_set in ("A", "B"):
            for start, phi in STARTS.items():
                cfg = replace(QuadrupedPlanConfig(), rule_set=rule_set, start_phi=phi)
                if SearchConfig is None:
                    cfg, search = replace(cfg, function=function), ()
                else:
                    search = (SearchConfig(function=function),)
                c0, w0 = time.process_time(), time.perf_counter()
                res = solve(cfg, *search, make_problem(cfg))
                dc, dw = time.process_time() - c0, time.perf_counter() - w0
                if not res.found:
                    raise SystemExit(f"({function}) {rule_set} {start}: {res.message}")
                expansions += res.expansions
                cpu += dc
                wall += dw
                plan = [list(s[:11]) for s in res.states]
                per[f"({function}) {rule_set} {start}"] = [res.expansions, dc, res.rules, plan]
    return expansions, cpu, wall, per


def baseline_once(src: Path) -> tuple[int, float, float, dict[str, list]]:
    env = dict(os.environ, PYTHONPATH=str(src))
    out = subprocess.run([sys.executable, __file__, "--table-json"], env=env, check=True,
                         capture_output=True, text=True, cwd=src.parent).stdout
    return tuple(json.loads(out))  # type: ignore[return-value]


def export(rev: str, into: Path) -> Path:
    """The package at ``rev`` in ``into/src``, its compiled successors built in place (as an
    install builds them: a baseline without them would time the Python fallback)."""
    archive = into / "src.tar"
    subprocess.run(["git", "-C", str(ROOT), "archive", "-o", str(archive), rev, "src",
                    "setup.py", "pyproject.toml", "README.md"], check=True)
    with tarfile.open(archive) as tar:
        tar.extractall(into, filter="data")
    subprocess.run([sys.executable, "setup.py", "-q", "build_ext", "--inplace"], cwd=into,
                   check=True, capture_output=True)
    return into / "src"


def report(label: str, run: tuple, repeat: int) -> None:
    expansions, cpu, wall, per = run
    print(f"{label}: best of {repeat}")
    for name, (n, dc, *_) in per.items():
        print(f"  {name:<10} {n:>7} expansions  {dc:6.3f} s CPU  {n / dc:>9.0f} exp/s")
    print(f"  12-configuration table: {cpu:.2f} s CPU, {wall:.2f} s wall (target < 10 s)")
    print(f"  expansions/s: {expansions / cpu:.0f} per CPU second, {expansions / wall:.0f} per "
          f"wall second (target >= 50,000); {expansions} expansions in all")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--baseline", default=None, help="git revision to compare with")
    ap.add_argument("--table-json", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.table_json:  # child process of --baseline
        print(json.dumps(table_once()))
        return
    best = base = None
    with tempfile.TemporaryDirectory() as tmp:
        src = export(args.baseline, Path(tmp)) if args.baseline else None
        for _ in range(args.repeat):  # alternate, so that both see the same load
            run = table_once()
            if best is None or run[1] < best[1]:
                best = run
            if src is not None:
                old = baseline_once(src)
                if base is None or old[1] < base[1]:
                    base = old
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    report("current", best, args.repeat)
    if base is not None:
        report(f"baseline {args.baseline}", base, args.repeat)
        same = all(base[3][k][0] == v[0] and base[3][k][2:] == [v[2], v[3]]
                   for k, v in json.loads(json.dumps(best[3])).items())
        print(f"speed-up (baseline CPU / current CPU, whole table): {base[1] / best[1]:.2f}x; "
              f"expansions and plans identical: {'yes' if same else 'NO'}")


if __name__ == "__main__":
    main()
