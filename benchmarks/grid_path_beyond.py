"""grid-path "beyond the paper": the best configuration over 10 random maps x 30 seeds.

Random 20x20 maps at 25% density (``random:20:0.25:K``, K = 0..9), success = final path
within 1% of the exact *free* optimum. Maps are spread over ``--procs`` processes (each run
is independent and seeded, so the figures do not depend on the process count); one line per
map and the aggregate row of ``evomotion grid-path study --experiment beyond`` are printed.

    python benchmarks/grid_path_beyond.py --seeds 30 --procs 2 \
        --row continuous+repair-r5 --update sync --pop 100 --generations 50 --pc 0.9 --pm 0.2
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from functools import partial

import numpy as np

from evomotion.studies.grid_path import experiments as ex
from evomotion.studies.grid_path.problem import GridPathProblem
from evomotion.studies.grid_path.solvers import all_optima


def one_map(k: int, a: argparse.Namespace) -> ex.Row:
    spec = f"random:20:0.25:{k}"
    problem = GridPathProblem(ex.beyond_config(a.row, spec))
    alg = ex.algorithm_for(f"cga-L5-{a.update}", a.pop, a.pc, a.pm)
    return ex.map_row(spec, a.row, problem, alg, a.generations, a.seeds,
                      all_optima(problem.map), "free")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=30)
    ap.add_argument("--maps", type=int, default=10)
    ap.add_argument("--procs", type=int, default=2)
    ap.add_argument("--row", default="continuous+repair-r5",  # old names too (seed-encoding)
                    choices=(*ex.BEYOND_ROWS, *getattr(ex, "OLD_ROW_NAMES", {})))
    ap.add_argument("--update", default="sync", choices=ex.POLICY_SHORT)
    ap.add_argument("--pop", type=int, default=100)
    ap.add_argument("--generations", type=int, default=50)
    ap.add_argument("--pc", type=float, default=0.9)
    ap.add_argument("--pm", type=float, default=0.2)
    a = ap.parse_args()
    t0 = time.perf_counter()
    with ProcessPoolExecutor(a.procs) as pool:
        rows = list(pool.map(partial(one_map, a=a), range(a.maps)))
    print(ex.HEADER)
    for r in rows:
        print(r.line(), flush=True)
    agg = ex.Row(f"random 20x20 x{a.maps}", a.row, float(np.mean([r.success for r in rows])),
                 float(np.mean([r.success_centres for r in rows])),
                 float(np.mean([r.mean_length for r in rows])),
                 float(np.mean([r.best_length for r in rows])),
                 float(np.mean([r.mean_conv for r in rows])),
                 float(np.mean([r.seconds for r in rows])))
    print(agg.line())
    n_ok = round(sum(r.success * a.seeds for r in rows))
    print(f"{n_ok}/{a.maps * a.seeds} runs within 1% of the free optimum; "
          f"wall {time.perf_counter() - t0:.0f} s with {a.procs} processes")


if __name__ == "__main__":
    main()
