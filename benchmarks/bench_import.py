"""Import cost of evomotion (issue 19): ``import evomotion`` loads no heavy package.

    python benchmarks/bench_import.py [--repeats 15]

Median wall time of a fresh interpreter running ``pass``, ``import evomotion``, ``import
evomotion; evomotion.CMAES`` (first use of an optimizer: numpy and the core) and ``import
evomotion; evomotion.get_study('humanoid-step')`` (a MuJoCo study), and the heavy modules
loaded by a bare ``import evomotion``.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time

CASES = {
    "python -c pass": "pass",
    "import evomotion": "import evomotion",
    "evomotion.CMAES": "import evomotion; evomotion.CMAES",
    "get_study('humanoid-step')": "import evomotion; evomotion.get_study('humanoid-step')",
}
HEAVY = ("numpy", "scipy", "mujoco", "matplotlib", "rich", "typer", "warp", "nicegui")


def wall(code: str) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True)
    return time.perf_counter() - t0


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeats", type=int, default=15)
    args = p.parse_args()
    times = {k: [] for k in CASES}
    for _ in range(args.repeats):  # interleaved, so load drifts hit every case alike
        for k, code in CASES.items():
            times[k].append(wall(code))
    base = statistics.median(times["python -c pass"])
    for k, ts in times.items():
        med = statistics.median(ts)
        print(f"{k:30s} {med * 1000:7.1f} ms  (+{(med - base) * 1000:6.1f} ms over python)")
    out = subprocess.run([sys.executable, "-c", "import sys, evomotion; print(' '.join(m for m"
                          f" in {HEAVY!r} if m in sys.modules))"], capture_output=True,
                         text=True, check=True).stdout.strip()
    print(f"heavy modules after 'import evomotion': {out or 'none'}")


if __name__ == "__main__":
    main()
