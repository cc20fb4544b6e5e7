"""evomotion: evolve and search robot motions (gaits, steps, kicks, reaches, plans, paths).

The public API (``import evomotion as em``), loaded lazily so that ``import evomotion`` stays
cheap (no numpy, MuJoCo or plotting until a name is used):

- the run loop: :func:`run` (a study name, a :class:`Study` or your own problem object, a
  config dict, an optional run folder; resume), :func:`load_run` -> :class:`Run`,
  :class:`RunResult`;
- problems: the :class:`Problem` protocol, :class:`GenomeSpec`, :class:`MeasureSpec`,
  :class:`Evaluation`;
- optimizers, usable with ``ask``/``tell`` and no run folder: :class:`GA`, :class:`CellularGA`,
  :class:`CMAES`, :class:`MAPElites`, :class:`CMAME` with their configs, the
  :class:`Optimizer` base, the registry :data:`ALGORITHMS` and :func:`make_optimizer`;
- studies: :data:`STUDIES`, :func:`get_study`, :class:`Study`; errors: :class:`InputError`.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

_EXPORTS = {
    "load_run": "evomotion.api", "Run": "evomotion.api",
    "problem_study": "evomotion.api", "RunResult": "evomotion.run.runner",
    "Problem": "evomotion.core.problem", "GenomeSpec": "evomotion.core.problem",
    "MeasureSpec": "evomotion.core.problem", "Evaluation": "evomotion.core.problem",
    "Optimizer": "evomotion.core.optimizer",
    "GA": "evomotion.core.ga", "GAConfig": "evomotion.core.ga",
    "CellularGA": "evomotion.core.cellular_ga", "CGAConfig": "evomotion.core.cellular_ga",
    "CMAES": "evomotion.core.cmaes", "CMAESConfig": "evomotion.core.cmaes",
    "MAPElites": "evomotion.core.map_elites", "MAPElitesConfig": "evomotion.core.map_elites",
    "CMAME": "evomotion.core.cma_me", "CMAMEConfig": "evomotion.core.cma_me",
    "ALGORITHMS": "evomotion.core.algorithms", "make_optimizer": "evomotion.core.algorithms",
    "STUDIES": "evomotion.studies", "get_study": "evomotion.studies",
    "Study": "evomotion.studies.base", "InputError": "evomotion.errors",
}

__all__ = [
    "ALGORITHMS", "CMAES", "CMAME", "GA", "STUDIES", "CGAConfig", "CMAESConfig",
    "CMAMEConfig", "CellularGA", "Evaluation", "GAConfig", "GenomeSpec", "InputError",
    "MAPElites", "MAPElitesConfig", "MeasureSpec", "Optimizer", "Problem", "Run", "RunResult",
    "Study", "__version__", "get_study", "load_run", "make_optimizer", "problem_study", "run",
]


def __getattr__(name: str) -> Any:
    if name == "run":  # the run-loop package, callable as evomotion.api.run
        return importlib.import_module("evomotion.run")
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'evomotion' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


if TYPE_CHECKING:  # what type checkers and IDEs see
    from evomotion.api import Run, load_run, problem_study, run
    from evomotion.core.algorithms import ALGORITHMS, make_optimizer
    from evomotion.core.cellular_ga import CellularGA, CGAConfig
    from evomotion.core.cma_me import CMAME, CMAMEConfig
    from evomotion.core.cmaes import CMAES, CMAESConfig
    from evomotion.core.ga import GA, GAConfig
    from evomotion.core.map_elites import MAPElites, MAPElitesConfig
    from evomotion.core.optimizer import Optimizer
    from evomotion.core.problem import Evaluation, GenomeSpec, MeasureSpec, Problem
    from evomotion.errors import InputError
    from evomotion.run.runner import RunResult
    from evomotion.studies import STUDIES, get_study
    from evomotion.studies.base import Study
