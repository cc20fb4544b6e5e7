"""Benchmark: planning time per replan of the receding-horizon walker (issue 16).

For each bundled world and rule set, ``--seeds`` walks with the default settings
(``RecedingConfig``: 800 expansions per replan, horizon 8, sub-goal 5 units ahead, the
default disturbances); every replan's time (route, sub-goal, heuristic, the search) is
recorded. Prints the median / 90th percentile / maximum per replan, expansions per second of
the replans. Target: median <= 50 ms for set A; expansions per second >= 50k. With
``--python`` every row is run a second time on the Python successors (``_walkcore`` off,
the same expansions) and the ratio of the two is printed, measured in the same run.

    python benchmarks/bench_replan.py [--seeds 5] [--rule-sets AB] [--shifts] [--python]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--rule-sets", default="AB")
    ap.add_argument("--shifts", action="store_true")
    ap.add_argument("--python", action="store_true",
                    help="also run the Python successors and print the ratio")
    args = ap.parse_args()

    from evomotion.studies.quadruped_plan.missions.mission import Mission, run_mission
    from evomotion.studies.quadruped_plan.rules import rules
    from evomotion.studies.quadruped_plan.rules.model import QuadrupedModel
    from evomotion.studies.quadruped_plan.worlds.world import bundled_worlds, load_world

    core = rules._walkcore
    print(f"load {os.getloadavg()[0]:.1f}, {time.strftime('%Y-%m-%d %H:%M')}, successors: "
          f"{'compiled (_walkcore)' if core is not None else 'Python'}")
    print(f"{'world':>9} {'set':>3} {'replans':>7} {'med ms':>7} {'p90 ms':>7} {'max ms':>7} "
          f"{'exp/s':>7} {'reached':>7}" + ("  python exp/s  ratio" if args.python else ""))

    def walks(name: str, rule_set: str) -> tuple[list[float], int, int]:
        ms, exp, reached = [], 0, 0
        for seed in range(args.seeds):
            m = Mission(load_world(name), QuadrupedModel(), rule_set, shifts=args.shifts)
            st = run_mission(m, np.random.default_rng(seed))
            ms += st.plan_ms
            exp += st.expansions
            reached += st.done == "reached"
        return ms, exp, reached

    for rule_set in args.rule_sets:
        all_ms, all_exp, all_py_ms = [], 0, 0.0
        for name in bundled_worlds():
            ms, exp, reached = walks(name, rule_set)
            all_ms += ms
            all_exp += exp
            a = np.array(ms)
            row = (f"{name:>9} {rule_set:>3} {len(a):>7} {np.median(a):>7.1f} "
                   f"{np.percentile(a, 90):>7.1f} {a.max():>7.1f} {exp / a.sum() * 1e3:>7.0f} "
                   f"{reached:>4}/{args.seeds}")
            if args.python:
                rules._walkcore = None
                try:
                    py_ms, py_exp, _ = walks(name, rule_set)
                finally:
                    rules._walkcore = core
                assert py_exp == exp, "the Python successors expanded other states"
                all_py_ms += sum(py_ms)
                row += f"  {py_exp / sum(py_ms) * 1e3:>12.0f}  {sum(py_ms) / a.sum():>5.2f}x"
            print(row, flush=True)
        a = np.array(all_ms)
        row = (f"{'all':>9} {rule_set:>3} {len(a):>7} {np.median(a):>7.1f} "
               f"{np.percentile(a, 90):>7.1f} {a.max():>7.1f} {all_exp / a.sum() * 1e3:>7.0f}")
        if args.python:
            row += (f"          {all_exp / all_py_ms * 1e3:>12.0f}  "
                    f"{all_py_ms / a.sum():>5.2f}x")
        print(row, flush=True)


if __name__ == "__main__":
    main()
