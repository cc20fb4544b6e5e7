"""Engine overhead against another revision: optimizer ask+tell and the run loop, same run.

Times, in this tree and in the package as committed at ``--baseline REV`` (``git archive``,
each in its own process, interleaved ``--repeat`` times, best of the repeats):

- ask+tell per generation with costs from a trivial function (only the optimizer is timed):
  GA (BLX-alpha + Gaussian + tournament, genome 200, population 100 and 1000), cellular GA
  (L5 line sweep and synchronous, population 400, genome 20), CMA-ES (default lambda,
  d = 10, 40, 200);
- the run loop: ``evomotion run functions`` defaults (sphere d = 30, population 100,
  200 generations) into a run folder, through ``run_study``.

    python benchmarks/bench_overhead.py --baseline d61c970 [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from baseline import export, run_child  # noqa: E402


def _loop(opt, rng, gens: int) -> float:
    state = opt.init(rng)
    x, state = opt.ask(state, rng)
    state = opt.tell(state, x, (x ** 2).sum(1), rng)
    t0 = time.perf_counter()
    n = 0
    while n < gens:
        x, state = opt.ask(state, rng)
        state = opt.tell(state, x, (x ** 2).sum(1), rng)
        done = getattr(opt, "end_of_generation", lambda s: True)(state)
        n += bool(done)
    return (time.perf_counter() - t0) / gens * 1e3


def measure() -> dict:
    import numpy as np

    from evomotion.core.algorithms import ALGORITHMS
    from evomotion.core.problem import GenomeSpec

    out = {}
    for pop, gens in ((100, 200), (1000, 30)):
        cls, make = ALGORITHMS["ga"]
        cfg = cls(pop_size=pop, crossover="blx_alpha", crossover_params={"alpha": 0.5},
                  mutation="gaussian", mutation_rate=0.1, selection="tournament",
                  selection_params={"k": 3})
        opt = make(GenomeSpec.box(200, -5, 5), cfg)
        out[f"GA pop {pop} d 200 (ms/gen)"] = _loop(opt, np.random.default_rng(0), gens)
    for update in ("line_sweep", "synchronous"):
        cls, make = ALGORITHMS["cga"]
        opt = make(GenomeSpec.box(20, -5, 5), cls(pop_size=400, update=update))
        out[f"cGA {update} pop 400 d 20 (ms/gen)"] = _loop(opt, np.random.default_rng(0), 30)
    for d in (10, 40, 200):
        cls, make = ALGORITHMS["cmaes"]
        opt = make(GenomeSpec.box(d, -5, 5), cls())
        out[f"CMA-ES d {d} (ms/gen)"] = _loop(opt, np.random.default_rng(0), 200)
    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study
    from evomotion.studies import get_study

    s = get_study("functions")
    import evomotion.run.plots  # noqa: F401 - matplotlib's import is not the loop's time
    with tempfile.TemporaryDirectory() as tmp:
        cfg = resolve_config(s, None, ["run.checkpoint_every=10"])
        t0 = time.perf_counter()
        run_study(s, cfg, Path(tmp) / "run", quiet=True)
        out["run functions defaults, run folder (s)"] = time.perf_counter() - t0
    return out


def run_in(src: Path | None) -> dict:
    return run_child(__file__, src, {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"})


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--baseline", default="HEAD")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--child", default=None)
    a = ap.parse_args()
    if a.child:
        Path(a.child).write_text(json.dumps(measure()))
        return
    with tempfile.TemporaryDirectory() as tmp:
        src = export(a.baseline, Path(tmp))
        old, new = [], []
        for _ in range(a.repeat):
            old.append(run_in(src))
            new.append(run_in(None))
    print(f"| measure | {a.baseline} | this tree | ratio (this / baseline) |\n|---|---|---|---|")
    for k in old[0]:
        o, n = min(r[k] for r in old), min(r[k] for r in new)
        print(f"| {k} | {o:.3f} | {n:.3f} | {n / o:.2f} |")


if __name__ == "__main__":
    main()
