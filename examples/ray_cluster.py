"""A study evaluated on a Ray cluster from Python (``pip install -e '.[ray]'``): with no
address a local Ray instance is started; pass ``run.address`` to join a running cluster.
The result is bit-identical to the serial evaluator.

    python examples/ray_cluster.py [OUT_DIR]
"""

import sys
from pathlib import Path

import evomotion as em


def main(out: str = "runs/ray") -> None:
    config = {"problem": {"name": "rastrigin", "dim": 20},
              "run": {"generations": 15, "seed": 3, "evaluator": "ray", "workers": 2}}
    on_ray = em.run("functions", config, Path(out) / "ray")
    serial = em.run("functions", {**config, "run": {**config["run"], "evaluator": "serial"}},
                    Path(out) / "serial")
    print(f"ray {on_ray.best_fitness:.6f}, serial {serial.best_fitness:.6f}")
    assert on_ray.best_fitness == serial.best_fitness


if __name__ == "__main__":
    main(*sys.argv[1:])
