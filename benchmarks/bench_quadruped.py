"""Benchmark: quadruped-plan search speed (seed 003).

Prints expansions per second of the seed's best-first search and the time to run the whole
12-configuration table (2 starts x rule sets A, B x functions 1-3). Both are given in CPU
seconds of this process (robust on a shared machine) and in wall seconds, with the load
average. Targets: >= 50,000 expansions/s; the table in < 10 s.

    python benchmarks/bench_quadruped.py [--repeat N]
"""

from __future__ import annotations

import argparse
import os
import time
from dataclasses import replace

from evomotion.studies.quadruped_plan.experiment import STARTS
from evomotion.studies.quadruped_plan.planner import QuadrupedPlanConfig, make_problem, solve


def table_once() -> tuple[int, float, float, dict[str, tuple[int, float]]]:
    expansions, cpu, wall, per = 0, 0.0, 0.0, {}
    for function in (1, 2, 3):
        for rule_set in ("A", "B"):
            for start, phi in STARTS.items():
                cfg = replace(QuadrupedPlanConfig(), function=function, rule_set=rule_set,
                              start_phi=phi)
                c0, w0 = time.process_time(), time.perf_counter()
                res = solve(cfg, make_problem(cfg))
                dc, dw = time.process_time() - c0, time.perf_counter() - w0
                if not res.found:
                    raise SystemExit(f"({function}) {rule_set} {start}: {res.message}")
                expansions += res.expansions
                cpu += dc
                wall += dw
                per[f"({function}) {rule_set} {start}"] = (res.expansions, dc)
    return expansions, cpu, wall, per


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    best = None
    for _ in range(args.repeat):
        run = table_once()
        if best is None or run[1] < best[1]:
            best = run
    expansions, cpu, wall, per = best
    for name, (n, dc) in per.items():
        print(f"  {name:<10} {n:>7} expansions  {dc:6.3f} s CPU  {n / dc:>9.0f} exp/s")
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; best of "
          f"{args.repeat}")
    print(f"12-configuration table: {cpu:.2f} s CPU, {wall:.2f} s wall (target < 10 s)")
    print(f"expansions/s: {expansions / cpu:.0f} per CPU second, {expansions / wall:.0f} per "
          f"wall second (target >= 50,000); {expansions} expansions in all")


if __name__ == "__main__":
    main()
