"""The ``functions`` study: the engine on classic benchmark functions."""

from __future__ import annotations

from evomotion.studies.base import Study
from evomotion.studies.functions.problem import FunctionProblem, FunctionsConfig

STUDY = Study(
    name="functions",
    description="Sphere, Rosenbrock, Rastrigin and Ackley in any dimension (engine check).",
    problem_config=FunctionsConfig,
    make_problem=FunctionProblem,
    defaults={
        "algorithm": {"pop_size": 100, "crossover": "blx_alpha", "mutation": "gaussian",
                      "mutation_rate": 0.1, "mutation_params": {"sigma": 0.001},
                      "selection": "tournament", "selection_params": {"k": 2},
                      "replacement": "plus"},
        "run": {"generations": 200},
    },
    smoke=(
        "problem.dim=4",
        "algorithm.pop_size=10",
    ),
)
