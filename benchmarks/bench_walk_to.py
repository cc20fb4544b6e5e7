"""``humanoid-repertoire walk-to`` with walk controllers (issue 34): the five targets of the
repertoire's table in docs/humanoid-repertoire.md plus two longer ones, walked closed loop by
each humanoid-walk run given (the NAO alone, nominal world); position and heading error
after standing 2 s, the time walked, falls.

    python benchmarks/bench_walk_to.py OMNIWALK_RUN [OMNIWALK_RUN ...]
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from evomotion.studies.humanoid_repertoire.controller_walk_to import controller_walk_to

TARGETS = [(0.3, 0.0, 0.0), (0.5, 0.2, 0.0), (0.6, -0.3, -30.0), (0.8, 0.0, 45.0),
           (0.2, 0.6, 90.0), (1.5, 0.5, 0.0), (2.0, -1.0, -90.0)]


def main() -> None:
    runs = [Path(a) for a in sys.argv[1:]]
    print("| target (x m, y m, θ°) | " + " | ".join(f"{r.name}: walked s, error, fell"
                                                  for r in runs) + " |")
    print("|---|" + "---|" * len(runs))
    for x, y, th in TARGETS:
        cells = []
        for run in runs:
            t0 = time.perf_counter()
            r = controller_walk_to(run, x, y, th)
            cells.append(f"{r['walk_s']:.1f} s, {100 * r['position_error_m']:.1f} cm, "
                         f"{r['heading_error_deg']:.1f}°, {'FELL' if r['fell'] else 'no'} "
                         f"({time.perf_counter() - t0:.1f} s wall)")
        print(f"| ({x:g}, {y:g}, {th:g}) | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
