from __future__ import annotations

import numpy as np
import pytest

from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.studies import get_study
from evomotion.studies.functions.problem import FUNCTIONS, FunctionProblem, FunctionsConfig


@pytest.mark.parametrize("name", sorted(FUNCTIONS))
def test_optimum_is_zero(name):
    p = FunctionProblem(FunctionsConfig(name=name, dim=5))
    ev = p.evaluate(p.optimum[None, :])
    assert ev.fitness[0] == pytest.approx(0.0, abs=1e-12)
    x = p.genome.sample(np.random.default_rng(0), 50)
    assert np.all(p.evaluate(x).fitness > 0)


def test_default_ga_solves_sphere_30d_within_200_generations(tmp_path):
    """Issue 2: mean best fitness within 1e-6 of 0 on sphere (dim 30), 200 gens x 100."""
    s = get_study("functions")
    best = []
    for seed in range(3):
        cfg = resolve_config(s, None, ["problem.name=sphere", "problem.dim=30",
                                       f"run.seed={seed}", "run.checkpoint_every=0"])
        assert cfg.algorithm.pop_size == 100 and cfg.run.generations == 200
        best.append(run_study(s, cfg, tmp_path / str(seed), quiet=True).best_fitness)
    assert np.mean(best) < 1e-6
