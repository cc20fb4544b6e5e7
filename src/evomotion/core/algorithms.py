"""Registry of ask/tell optimizers: ``name -> (config dataclass, factory)``.

Every factory is ``factory(genome, cfg, *, mutate=None)``: ``genome`` a
:class:`evomotion.core.problem.GenomeSpec`, ``cfg`` an instance of the config dataclass, and
``mutate(x[n, d], rng, rate) -> x'`` an optional problem-supplied mutation
(:data:`evomotion.core.optimizer.MutateFn`). The GA and the cellular GA use it in place of the
registry mutation; CMA-ES has no mutation operator and raises ``ValueError`` when given one.
The quality-diversity optimizers (MAP-Elites, CMA-ME; their configs say ``needs_measures``)
also take ``measures=``, the problem's :class:`~evomotion.core.problem.MeasureSpec`.
"""

from __future__ import annotations

from collections.abc import Callable

from evomotion.core.cellular_ga import CGAConfig, make_cga
from evomotion.core.cma_me import CMAMEConfig, make_cma_me
from evomotion.core.cmaes import CMAESConfig, make_cmaes
from evomotion.core.ga import GAConfig, make_ga
from evomotion.core.map_elites import MAPElitesConfig, make_map_elites
from evomotion.core.optimizer import Optimizer

ALGORITHMS: dict[str, tuple[type, Callable[..., Optimizer]]] = {
    "ga": (GAConfig, make_ga),
    "cga": (CGAConfig, make_cga),
    "cmaes": (CMAESConfig, make_cmaes),
    "map_elites": (MAPElitesConfig, make_map_elites),
    "cma_me": (CMAMEConfig, make_cma_me),
}
