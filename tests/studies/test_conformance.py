"""One conformance check over every registered study (like gymnasium's check_env)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from evomotion.core.algorithms import ALGORITHMS
from evomotion.core.problem import Problem
from evomotion.run.config import resolve_config
from evomotion.studies import STUDIES, get_study


@pytest.mark.parametrize("name", sorted(STUDIES))
def test_study_conforms(name):
    s = get_study(name)
    assert s.name == name and s.description and len(s.description.splitlines()) == 1
    assert dataclasses.is_dataclass(s.problem_config)
    assert s.problem_config.__dataclass_params__.frozen
    cfg = resolve_config(s)  # the study's defaults resolve against the typed config
    assert cfg.algorithm.name in ALGORITHMS
    if s.run is not None:
        return  # search/multi-phase studies drive their own loop (tested in their folders)
    problem = s.make_problem(cfg.problem)
    assert isinstance(problem, Problem)
    g = problem.genome
    assert g.lower.shape == g.upper.shape == (g.dim,) and np.all(g.lower <= g.upper)
    assert problem.sense in ("min", "max")
    x = g.sample(np.random.default_rng(0), 2)
    ev1, ev2 = problem.evaluate(x), problem.evaluate(x)
    assert ev1.fitness.shape == (2,)
    assert set(ev1.metrics) >= set(problem.metric_names)
    for k in problem.metric_names:
        assert np.shape(ev1.metrics[k])[0] == 2
    np.testing.assert_array_equal(ev1.fitness, ev2.fitness)  # deterministic
    # batch composition must not change an individual's result (evaluator equivalence)
    ev_single = problem.evaluate(x[1:2])
    np.testing.assert_array_equal(ev_single.fitness, ev1.fitness[1:2])
