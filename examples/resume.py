"""A run interrupted (here: a simulated Ctrl-C in generation 7) and resumed is bit-identical to
a run that was never interrupted.

    python examples/resume.py [OUT_DIR]
"""

import sys
from pathlib import Path

import numpy as np

import evomotion as em


class Rastrigin:
    """Rastrigin in 10 dimensions; ``interrupt_at`` raises KeyboardInterrupt (like Ctrl-C)
    in that evaluation call, once."""

    genome = em.GenomeSpec(lower=np.full(10, -5.12), upper=np.full(10, 5.12))
    sense = "min"
    metric_names = ()

    def __init__(self, interrupt_at: int = -1) -> None:
        self.calls, self.interrupt_at = 0, interrupt_at

    def evaluate(self, x: np.ndarray) -> em.Evaluation:
        self.calls += 1
        if self.calls == self.interrupt_at:
            raise KeyboardInterrupt
        return em.Evaluation(10 * x.shape[1] + (x**2 - 10 * np.cos(2 * np.pi * x)).sum(axis=1))


def main(out: str = "runs/resume") -> None:
    config = {"algorithm": {"name": "ga", "pop_size": 50},
              "run": {"generations": 20, "seed": 4, "checkpoint_every": 5}}
    whole = em.run(Rastrigin(), config, Path(out) / "whole")
    cut = em.run(Rastrigin(interrupt_at=8), config, Path(out) / "cut")
    print(f"interrupted: {cut.stop_reason} at generation {cut.generation}")
    resumed = em.run(Rastrigin(), None, Path(out) / "cut", resume=True)
    a, b = em.load_run(Path(out) / "whole"), em.load_run(Path(out) / "cut")
    same = all(np.array_equal(a.stats[c], b.stats[c]) for c in ("best", "mean", "min"))
    print(f"uninterrupted {whole.best_fitness:.6f}, resumed {resumed.best_fitness:.6f}, "
          f"stats identical: {same}")
    assert same and whole.best_fitness == resumed.best_fitness


if __name__ == "__main__":
    main(*sys.argv[1:])
