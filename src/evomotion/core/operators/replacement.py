"""Survivor selection: generational with elites, and (mu + lambda).

Signature: ``fn(pop, cost, children, child_cost, n_elite) -> (new_pop, new_cost)``.
Ties keep the earlier individual (stable sorts), so results are deterministic.

Sources: elitist generational replacement (De Jong 1975); (mu+lambda) selection
(Schwefel 1981, *Numerical Optimization of Computer Models*).
"""

from __future__ import annotations

from functools import partial

import numpy as np

from evomotion.core.registry import register

REPLACEMENTS: dict = {}
_reg = partial(register, REPLACEMENTS)


@_reg("generational")
def generational(pop, cost, children, child_cost, n_elite: int):
    """The ``n_elite`` best parents survive; the rest of the slots go to the best children."""
    mu = pop.shape[0]
    n_elite = int(min(max(n_elite, 0), mu))
    elite = np.argsort(cost, kind="stable")[:n_elite]
    rest = np.argsort(child_cost, kind="stable")[: mu - n_elite]
    new_pop = np.concatenate([pop[elite], children[rest]])
    new_cost = np.concatenate([cost[elite], child_cost[rest]])
    return new_pop, new_cost


@_reg("plus")
def plus(pop, cost, children, child_cost, n_elite: int = 0):
    """(mu + lambda): the ``mu`` best of parents and children survive."""
    mu = pop.shape[0]
    allp = np.concatenate([pop, children])
    allc = np.concatenate([cost, child_cost])
    keep = np.argsort(allc, kind="stable")[:mu]
    return allp[keep], allc[keep]
