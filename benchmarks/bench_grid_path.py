"""grid-path benchmark: wall time per run on 20x20 and cGA generations/s vs pure Python.

1. Median wall time of one run on the bundled 20x20 map with the paper's settings
   (population 400, 100 generations, m = 1.05), cGA line sweep (the paper) and synchronous.
2. Generations per second of the same cGA (L5, roulette mate, one-point crossover, the
   paper's validity-keeping mutation, replace-if-better) at population 400, for the line
   sweep and for the synchronous update: the vectorised implementation (20 generations,
   median of 3) against a pure-Python one that updates one cell at a time (the synchronous
   one building the new population from the old) with a pure-Python exact segment test.

    python benchmarks/bench_grid_path.py [--runs 5] [--py-generations 2]
"""

from __future__ import annotations

import argparse
import math
import random
import statistics
import time

import numpy as np

from evomotion.core.cellular_ga import CGAConfig
from evomotion.core.neighbourhoods import neighbour_table

try:
    from evomotion.studies.grid_path.experiments import evolve
except ImportError:  # a tree from before issue 32 (the in-memory runner in run/)
    try:
        from evomotion.studies.grid_path.outcome import evolve
    except ImportError:  # a tree from before the one run loop (PYTHONPATH=... for a baseline)
        from evomotion.studies.grid_path.driver import evolve
from evomotion.studies.grid_path.problem import GridPathConfig, GridPathProblem


def py_segment_valid(blocked, w, h, x0, y0, x1, y1) -> bool:
    """Closed rule, one segment, pure Python (same cut-and-midpoint test as geometry.py)."""
    ts = [0.0, 1.0]
    for a0, a1 in ((x0, x1), (y0, y1)):
        if a1 != a0:
            k = math.ceil(min(a0, a1) - 1e-9)
            while k <= max(a0, a1) + 1e-9:
                ts.append(min(max((k - a0) / (a1 - a0), 0.0), 1.0))
                k += 1
    ts.sort()
    pts = ts + [(a + b) / 2 for a, b in zip(ts, ts[1:], strict=False)]
    for t in pts:
        x, y = x0 + t * (x1 - x0), y0 + t * (y1 - y0)
        xs = [round(x) - 1, round(x)] if abs(x - round(x)) < 1e-9 else [math.floor(x)]
        ys = [round(y) - 1, round(y)] if abs(y - round(y)) < 1e-9 else [math.floor(y)]
        for cx in xs:
            for cy in ys:
                if not (0 <= cx < w and 0 <= cy < h) or blocked[cy][cx]:
                    return False
    return True


class PurePythonCGA:
    """The same cGA, one cell at a time, plain Python lists and ``random``: ``synchronous``
    breeds every cell from the old population and replaces them all at the end, otherwise
    cells are updated in place in row-major order (the line sweep)."""

    def __init__(self, problem: GridPathProblem, pop: list[list[float]], pc: float, pm: float,
                 synchronous: bool = False):
        self.p = problem
        self.synchronous = synchronous
        self.enc = problem.enc
        self.blocked = problem.map.blocked.tolist()
        self.w, self.h = problem.map.width, problem.map.height
        self.pop = [list(x) for x in pop]
        self.pc, self.pm = pc, pm
        self.nbr = neighbour_table("L5", 20, 20).tolist()
        self.feet = self.enc.foot_points().tolist()
        self.nrm = self.enc.normal.tolist()
        self.pieces = [[(lo, hi) for lo, hi in zip(problem.operators.lo[g][:c],
                                                  problem.operators.hi[g][:c], strict=True)]
                       for g, c in enumerate(problem.operators.count.tolist())]
        self.cost = [self.fitness(x) for x in self.pop]

    def point(self, g: int, y: float) -> tuple[float, float]:
        f = self.feet[g]
        return (math.floor(f[0] + y * self.nrm[0]) + 0.5, math.floor(f[1] + y * self.nrm[1]) + 0.5)

    def poly(self, x: list[float]) -> list[tuple[float, float]]:
        return ([tuple(self.enc.start)] + [self.point(g, y) for g, y in enumerate(x)]
                + [tuple(self.enc.goal)])

    def valid(self, a, b) -> bool:
        return py_segment_valid(self.blocked, self.w, self.h, a[0], a[1], b[0], b[1])

    def fitness(self, x: list[float]) -> float:
        pts = self.poly(x)
        f = 0.0
        for a, b in zip(pts, pts[1:], strict=False):
            f += math.hypot(b[0] - a[0], b[1] - a[1])
            if not self.valid(a, b):
                f += self.p.penalty
        return f

    def generation(self) -> None:
        # the synchronous policy reads the old population and writes a new one
        pop, cost = self.pop, self.cost
        if self.synchronous:
            self.pop, self.cost = list(pop), list(cost)
        for c in range(len(pop)):
            nb = self.nbr[c][1:]
            costs = [cost[j] for j in nb]
            hi, lo = max(costs), min(costs)
            wts = [hi - v + (1e-3 * (hi - lo) if hi > lo else 1.0) for v in costs]
            mate = pop[random.choices(nb, weights=wts)[0]]
            child = list(pop[c])
            if random.random() < self.pc:
                cut = random.randrange(1, len(child))
                child = (child[:cut] + mate[cut:]) if random.random() < 0.5 else \
                    (mate[:cut] + child[cut:])
            if random.random() < self.pm:
                i = random.randrange(len(child) + 1)
                if i > 0:
                    g = i - 1
                    pts = self.poly(child)
                    for _ in range(self.p.operators.retries):
                        lo_, hi_ = random.choice(self.pieces[g])
                        y = lo_ + (hi_ - lo_) * random.uniform(0.05, 0.95)
                        q = self.point(g, y)
                        if self.valid(pts[g], q) and self.valid(q, pts[g + 2]):
                            child[g] = y
                            break
            f = self.fitness(child)
            if f < cost[c]:
                self.pop[c], self.cost[c] = child, f


def _timed(fn):
    """``(result, wall seconds, CPU seconds of this process)`` of ``fn()``."""
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w, time.process_time() - c


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--py-generations", type=int, default=2)
    a = ap.parse_args()
    p = GridPathProblem(GridPathConfig(map="seed20", m=1.05))
    for update in ("line_sweep", "synchronous"):
        cfg = CGAConfig(pop_size=400, update=update, crossover_rate=0.9, mutation_rate=0.2)
        t = [_timed(lambda cfg=cfg, s=s: evolve(p, cfg, s, 100))[1:] for s in range(a.runs)]
        print(f"20x20 paper map, pop 400, 100 generations, cGA {update}: median "
              f"{statistics.median(w for w, _ in t):.2f} s wall "
              f"({statistics.median(c for _, c in t):.2f} s CPU) per run over {a.runs} runs")
    gens = 20
    pop0 = p.operators.initial_population(400, np.random.default_rng(0))
    for update in ("line_sweep", "synchronous"):
        cfg = CGAConfig(pop_size=400, update=update, crossover_rate=0.9, mutation_rate=0.2)
        rates = []
        for _ in range(3):  # median of 3 (each run is only ~0.1 s)
            r, w1, c1 = _timed(lambda cfg=cfg: evolve(p, cfg, 0, gens))
            _, w0, c0 = _timed(lambda cfg=cfg: evolve(p, cfg, 0, 0))  # initialisation, end
            rates.append((gens / (w1 - w0), gens / (c1 - c0)))
        vec = statistics.median(v for v, _ in rates)
        vec_cpu = statistics.median(v for _, v in rates)
        random.seed(0)
        py = PurePythonCGA(p, pop0.tolist(), 0.9, 0.2, synchronous=update == "synchronous")
        _, pw, pc = _timed(lambda py=py: [py.generation() for _ in range(a.py_generations)])
        pyrate, pyrate_cpu = a.py_generations / pw, a.py_generations / pc
        print(f"cGA {update}, pop 400: vectorised {vec:.2f} gen/s, pure Python "
              f"{pyrate:.3f} gen/s -> {vec / pyrate:.1f}x wall; CPU time: {vec_cpu:.2f} vs "
              f"{pyrate_cpu:.3f} gen/s -> {vec_cpu / pyrate_cpu:.1f}x (best {r.length:.4f} vs "
              f"{min(py.cost):.4f})")

if __name__ == "__main__":
    main()
