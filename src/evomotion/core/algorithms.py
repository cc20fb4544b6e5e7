"""Registry of ask/tell optimizers: name -> (config dataclass, factory(genome, cfg))."""

from __future__ import annotations

from evomotion.core.cellular_ga import CGAConfig, make_cga
from evomotion.core.cmaes import CMAESConfig, make_cmaes
from evomotion.core.ga import GA, GAConfig

ALGORITHMS: dict[str, tuple[type, object]] = {
    "ga": (GAConfig, GA),
    "cga": (CGAConfig, make_cga),
    "cmaes": (CMAESConfig, make_cmaes),
}
