"""Your own objective through the run loop: CMA-ES on Rosenbrock, a run folder, a resume.

    python examples/own_objective.py [OUT_DIR]
"""

import sys

import numpy as np

import evomotion as em


class Rosenbrock:
    """The Rosenbrock function in 8 dimensions (minimum 0 at x = 1)."""

    genome = em.GenomeSpec(lower=np.full(8, -3.0), upper=np.full(8, 3.0))
    sense = "min"
    metric_names = ("distance_to_optimum",)

    def evaluate(self, x: np.ndarray) -> em.Evaluation:
        f = (100 * (x[:, 1:] - x[:, :-1] ** 2) ** 2 + (1 - x[:, :-1]) ** 2).sum(axis=1)
        return em.Evaluation(f, {"distance_to_optimum": np.linalg.norm(x - 1, axis=1)})


def main(out: str = "runs/rosenbrock") -> None:
    config = {"algorithm": {"name": "cmaes", "sigma0": 1.0},
              "run": {"generations": 100, "seed": 1, "checkpoint_every": 25}}
    first = em.run(Rosenbrock(), config, out)
    more = em.run(Rosenbrock(), {"run": {"generations": 300}}, out, resume=True)
    run = em.load_run(out)
    print(f"after {first.generation} generations: {first.best_fitness:.3g}; after "
          f"{more.generation}: {more.best_fitness:.3g} (best.json: {run.best_fitness:.3g})")


if __name__ == "__main__":
    main(*sys.argv[1:])
