"""Registry of ask/tell optimizers: ``name -> (config dataclass, factory)``.

Every factory is ``factory(genome, cfg, *, mutate=None)``: ``genome`` a
:class:`evomotion.core.problem.GenomeSpec`, ``cfg`` an instance of the config dataclass, and
``mutate(x[n, d], rng, rate) -> x'`` an optional problem-supplied mutation
(:data:`evomotion.core.optimizer.MutateFn`). The GA and the cellular GA use it in place of the
registry mutation; CMA-ES and the evolution strategies of :mod:`evomotion.core.es` (OpenAI-ES,
ARS, PGPE, SNES) have no mutation operator and raise ``ValueError`` when given one.
The quality-diversity optimizers (MAP-Elites, CMA-ME; their configs say ``needs_measures``)
also take ``measures=``, the problem's :class:`~evomotion.core.problem.MeasureSpec`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

from evomotion.core.cellular_ga import CGAConfig, make_cga
from evomotion.core.cma_me import CMAMEConfig, make_cma_me
from evomotion.core.cmaes import CMAESConfig, make_cmaes
from evomotion.core.es.ars import ARSConfig, make_ars
from evomotion.core.es.openai_es import OpenAIESConfig, make_openai_es
from evomotion.core.es.pgpe import PGPEConfig, make_pgpe
from evomotion.core.es.snes import SNESConfig, make_snes
from evomotion.core.ga import GAConfig, make_ga
from evomotion.core.map_elites import MAPElitesConfig, make_map_elites
from evomotion.core.optimizer import MutateFn, Optimizer
from evomotion.core.problem import GenomeSpec, MeasureSpec
from evomotion.core.registry import lookup
from evomotion.errors import InputError

ALGORITHMS: dict[str, tuple[type, Callable[..., Optimizer]]] = {
    "ga": (GAConfig, make_ga),
    "cga": (CGAConfig, make_cga),
    "cmaes": (CMAESConfig, make_cmaes),
    "map_elites": (MAPElitesConfig, make_map_elites),
    "cma_me": (CMAMEConfig, make_cma_me),
    "openai_es": (OpenAIESConfig, make_openai_es),
    "ars": (ARSConfig, make_ars),
    "pgpe": (PGPEConfig, make_pgpe),
    "snes": (SNESConfig, make_snes),
}


def make_optimizer(name: str, genome: GenomeSpec, config: Any = None, *,
                   mutate: MutateFn | None = None, measures: MeasureSpec | None = None,
                   **settings: Any) -> Optimizer:
    """The registered optimizer ``name`` over ``genome`` with ``config`` (its config
    dataclass) or, without one, its config built from ``settings``, e.g.
    ``make_optimizer("cmaes", genome, sigma0=0.3, pop_size=16)``; for use with ``ask``/``tell``
    and no run folder. A quality-diversity optimizer (``map_elites``, ``cma_me``) needs
    ``measures`` and its ``tell`` takes ``measures=``. An unknown name or setting is an
    :class:`~evomotion.errors.InputError`."""
    cls, factory = lookup(ALGORITHMS, "algorithm", name)
    if not isinstance(genome, GenomeSpec):
        raise InputError(f"{name}: genome must be a GenomeSpec, got {type(genome).__name__}")
    if config is not None and settings:
        raise InputError(f"{name}: give either a config or settings, not both")
    if config is None:
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(settings) - known)
        if unknown:
            raise InputError(f"{name}: unknown setting {unknown[0]!r}; valid: "
                             f"{', '.join(sorted(known))}")
        config = cls(**settings)
    if not isinstance(config, cls):
        raise InputError(f"{name}: config must be a {cls.__name__}, got "
                         f"{type(config).__name__}")
    kwargs: dict[str, Any] = {}
    if mutate is not None:
        kwargs["mutate"] = mutate
    if getattr(config, "needs_measures", False):
        if measures is None:
            raise InputError(f"{name}: a quality-diversity optimizer needs measures= (a "
                             "MeasureSpec: names, lower, upper, bins)")
        kwargs["measures"] = measures
    try:
        return factory(genome, config, **kwargs)
    except ValueError as e:  # a setting out of range (the configs' own checks)
        if isinstance(e, InputError):
            raise
        raise InputError(f"{name}: {e}") from None
