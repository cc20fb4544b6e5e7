"""Vectorized variation and selection operators, each in a plain-dict registry."""

from evomotion.core.operators.crossover import CROSSOVERS
from evomotion.core.operators.mutation import MUTATIONS
from evomotion.core.operators.replacement import REPLACEMENTS
from evomotion.core.operators.selection import SELECTIONS

__all__ = ["CROSSOVERS", "MUTATIONS", "SELECTIONS", "REPLACEMENTS"]
