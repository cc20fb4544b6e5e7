"""Benchmark: planning time per replan of the receding-horizon walker (issue 16).

For each bundled world and rule set, ``--seeds`` walks with the default settings
(``RecedingConfig``: 800 expansions per replan, horizon 8, sub-goal 5 units ahead, the
default disturbances); every replan's time (route, sub-goal, heuristic, the search) is
recorded. Prints the median / 90th percentile / maximum per replan, expansions per second of
the replans, and the share of replans whose search hit the expansion budget. Target: median
<= 50 ms for set A; expansions per second >= 50k.

    python benchmarks/bench_replan.py [--seeds 5] [--rule-sets AB] [--shifts]
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
    args = ap.parse_args()

    from evomotion.studies.quadruped_plan.mission import Mission, run_mission
    from evomotion.studies.quadruped_plan.model import QuadrupedModel
    from evomotion.studies.quadruped_plan.world import bundled_worlds, load_world

    print(f"load {os.getloadavg()[0]:.1f}, {time.strftime('%Y-%m-%d %H:%M')}")
    print(f"{'world':>9} {'set':>3} {'replans':>7} {'med ms':>7} {'p90 ms':>7} {'max ms':>7} "
          f"{'exp/s':>7} {'reached':>7}")
    for rule_set in args.rule_sets:
        all_ms, all_exp = [], 0
        for name in bundled_worlds():
            ms, exp, reached = [], 0, 0
            for seed in range(args.seeds):
                m = Mission(load_world(name), QuadrupedModel(), rule_set, shifts=args.shifts)
                st = run_mission(m, np.random.default_rng(seed))
                ms += st.plan_ms
                exp += st.expansions
                reached += st.done == "reached"
            all_ms += ms
            all_exp += exp
            a = np.array(ms)
            print(f"{name:>9} {rule_set:>3} {len(a):>7} {np.median(a):>7.1f} "
                  f"{np.percentile(a, 90):>7.1f} {a.max():>7.1f} {exp / a.sum() * 1e3:>7.0f} "
                  f"{reached:>4}/{args.seeds}")
        a = np.array(all_ms)
        print(f"{'all':>9} {rule_set:>3} {len(a):>7} {np.median(a):>7.1f} "
              f"{np.percentile(a, 90):>7.1f} {a.max():>7.1f} {all_exp / a.sum() * 1e3:>7.0f}")


if __name__ == "__main__":
    main()
