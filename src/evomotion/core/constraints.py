"""Feasibility-first ranking of constrained solutions (Deb, "An efficient constraint handling
method for genetic algorithms", Comput. Methods Appl. Mech. Eng. 186, 2000, sec. 3).

Deb's three rules: a feasible solution beats an infeasible one; of two feasible solutions the
better objective wins; of two infeasible ones the smaller constraint violation wins. For a
rank-based optimizer (CMA-ES ranks its samples, tournaments compare pairs) the rules are exactly
a ranking by the scalar :func:`feasibility_first`, which puts every infeasible solution below
every feasible one and orders the infeasible ones by violation alone. So a constraint becomes
part of the optimizer's selection, not a penalty traded against the objective: no infeasible
solution, however good its objective, is ever selected over a feasible one, and the best of a
run is feasible whenever any evaluated solution was.

The objective must be bounded on the feasible set: ``floor`` is a value no feasible objective
goes below (objectives under it are clipped to it, which only ties them). Violations are
resolved to the float spacing at ``|floor| + 1 + violation`` (about 4e-15 for a floor of -20):
two violations closer than that tie.
"""

from __future__ import annotations

import numpy as np

from evomotion.core.problem import Sense


def feasibility_first(objective: np.ndarray, violation: np.ndarray, sense: Sense,
                      floor: float) -> np.ndarray:
    """Scalar fitness (in ``sense``) ranking solutions by Deb's rules.

    ``violation >= 0`` (0: feasible). Maximising, feasible solutions keep
    ``max(objective, floor)`` and infeasible ones get ``floor - 1 - violation``; minimising,
    mirrored (``min(objective, floor)``, ``floor + 1 + violation``). A NaN violation or a NaN
    objective counts as infeasible with infinite violation (the worst)."""
    obj = np.asarray(objective, dtype=float)
    v = np.asarray(violation, dtype=float)
    v = np.where(np.isnan(v) | np.isnan(obj), np.inf, np.maximum(v, 0.0))
    feasible = v <= 0.0
    if sense == "max":
        return np.where(feasible, np.maximum(obj, floor), floor - 1.0 - v)
    return np.where(feasible, np.minimum(obj, floor), floor + 1.0 + v)


def is_feasible(fitness: np.ndarray, sense: Sense, floor: float) -> np.ndarray:
    """Which fitness values of :func:`feasibility_first` belong to feasible solutions."""
    f = np.asarray(fitness, dtype=float)
    return f >= floor if sense == "max" else f <= floor
