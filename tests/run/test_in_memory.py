"""run_in_memory: one configuration through the run loop without a folder gives what a run with
a folder gives (best genome, fitness, stats rows), uses the study's own methods and a given
evaluator, and builds the problem when only its factory is given."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

import evomotion as em
from evomotion.core.ga import GAConfig
from evomotion.errors import InputError
from evomotion.run.ask_tell import AskTellDriver, make_optimizer
from evomotion.run.config import Config, RunSection
from evomotion.run.evaluators import SerialEvaluator
from evomotion.run.in_memory import run_in_memory
from evomotion.run.stats import read_stats


class Sphere:
    genome = em.GenomeSpec(lower=np.full(3, -2.0), upper=np.full(3, 2.0))
    sense = "min"
    metric_names = ("norm",)

    def evaluate(self, x):
        return em.Evaluation((x**2).sum(axis=1), {"norm": np.linalg.norm(x, axis=1)})


@dataclass(frozen=True)
class SphereConfig:
    offset: float = 0.0


def config(algorithm=None, generations: int = 5) -> Config:
    return Config("sphere", RunSection(seed=3, generations=generations, checkpoint_every=0),
                  algorithm or GAConfig(pop_size=12), SphereConfig())


def test_same_result_as_a_run_with_a_folder(tmp_path):
    mem = run_in_memory(config(), Sphere())
    disk = em.run(Sphere(), {"algorithm": {"name": "ga", "pop_size": 12},
                             "run": {"seed": 3, "generations": 5, "checkpoint_every": 0}},
                  tmp_path / "run")
    assert mem.out_dir is None and mem.stop_reason == "generations"
    np.testing.assert_array_equal(mem.best_genome, disk.best_genome)
    assert mem.best_fitness == disk.best_fitness
    stats = read_stats(tmp_path / "run" / "stats.csv")
    assert len(mem.rows) == 6 == len(stats["generation"])
    for col in ("generation", "evaluations", "best", "mean", "min", "best_so_far", "diversity"):
        np.testing.assert_array_equal([r[col] for r in mem.rows], stats[col], err_msg=col)
    assert not any(tmp_path.glob("*.txt"))


def test_api_run_without_a_folder_is_the_in_memory_run():
    via_api = em.run(Sphere(), {"algorithm": {"name": "ga", "pop_size": 12},
                                "run": {"seed": 3, "generations": 5}})
    mem = run_in_memory(config(), Sphere())
    np.testing.assert_array_equal(via_api.best_genome, mem.best_genome)
    from evomotion.api import run_in_memory as exported

    assert exported is run_in_memory


def test_the_study_own_method_and_a_given_evaluator():
    @dataclass(frozen=True)
    class MineConfig:
        name: str = "mine"

    built = []

    def make_driver(problem, cfg):
        built.append(cfg.algorithm)
        return AskTellDriver(problem, make_optimizer(problem, GAConfig(pop_size=8)))

    class Counting(SerialEvaluator):
        calls = 0
        closed = False

        def __call__(self, genomes):
            self.calls += 1
            return super().__call__(genomes)

        def close(self):
            self.closed = True

    problem = Sphere()
    ev = Counting(lambda _cfg: problem, None)
    res = run_in_memory(config(MineConfig(), generations=2), problem,
                        algorithms={"mine": (MineConfig, make_driver)}, evaluator=ev)
    assert built == [MineConfig()] and res.generation == 2 and res.rows[0]["evaluations"] == 8
    assert ev.calls == 3 and not ev.closed  # the caller's evaluator stays open


def test_the_problem_is_built_by_its_factory_when_not_given():
    seen = []

    def make_problem(cfg):
        seen.append(cfg)
        return Sphere()

    res = run_in_memory(config(), make_problem=make_problem)
    assert seen == [SphereConfig()] and np.isfinite(res.best_fitness)
    with pytest.raises(InputError, match="give the problem or make_problem"):
        run_in_memory(config())
