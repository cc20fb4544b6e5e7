"""``[algorithm]`` of a quadruped-plan search (``name = "search"``): the method and budgets.

Methods: ``best-first`` (the paper's algorithm with its evaluation function 1, 2 or 3 and
constants ``k1``-``k3``, Section 3 of the source paper), ``astar`` (A* on plan length with the
admissible heuristic of :mod:`..rules.heuristic`) and ``weighted-astar`` (f = g + weight h);
``heuristic_gain`` picks the heuristic's rotation bound. These settings were in ``[problem]``
before issue 32; the old keys are still read (``Study.moved_keys``, with a note).
The duplicate grids ``problem.pos_grid`` / ``problem.angle_grid`` stay in ``[problem]``: they
define the state space (which states are the same), not how it is searched.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from evomotion.core.checks import check_fields, check_number, inf_ok
from evomotion.errors import InputError
from evomotion.studies.quadruped_plan.rules.evaluation import PAPER_CONSTANTS
from evomotion.studies.quadruped_plan.rules.heuristic import GAINS

METHODS = ("best-first", "astar", "weighted-astar")
#: the keys that moved from ``[problem]`` to ``[algorithm]`` (issue 32)
SEARCH_KEYS = ("method", "function", "k1", "k2", "k3", "weight", "heuristic_gain",
               "max_expansions", "max_seconds")
MAX_CONSTANT = 1e6  # the largest paper constant or weight


@dataclass(frozen=True)
class SearchConfig:
    """``[algorithm]`` of quadruped-plan: the search stepped in batches of expansions.

    ``k1``/``k2``/``k3`` < 0 mean the paper's constants for ``function`` and the rule set.
    ``max_seconds = inf``: no time limit (the only float that may be infinite).
    """

    name: str = "search"
    batch_expansions: int = 2_000  # expansions per step (a stats row, a checkpoint unit)
    method: str = "best-first"
    function: int = 3
    k1: float = -1.0
    k2: float = -1.0
    k3: float = -1.0
    weight: float = 3.0
    heuristic_gain: str = "analytic"
    max_expansions: int = 200_000
    max_seconds: float = inf_ok(60.0, "no time limit")

    def validate(self) -> None:
        """One-line :class:`InputError` for impossible settings."""
        check_fields(self, "algorithm")
        for key in ("k1", "k2", "k3"):  # < 0: the paper's constant
            check_number(f"algorithm.{key}", getattr(self, key), hi=MAX_CONSTANT)
        check_number("algorithm.weight", self.weight, lo=1.0, hi=MAX_CONSTANT)
        check_number("algorithm.max_seconds", self.max_seconds, lo=0.0, allow_inf=True)
        if self.max_seconds == -math.inf:
            raise InputError("algorithm.max_seconds: expected >= 0 (inf: no time limit), "
                             "got -inf")
        if self.method not in METHODS:
            raise InputError(f"algorithm.method: expected one of {', '.join(METHODS)}, "
                             f"got {self.method!r}")
        if self.function not in (1, 2, 3):
            raise InputError(f"algorithm.function: expected 1, 2 or 3, got {self.function}")
        if self.max_expansions < 0 or self.max_seconds < 0:
            raise InputError("algorithm.max_expansions and algorithm.max_seconds must be >= 0")
        if self.heuristic_gain not in GAINS:
            raise InputError(f"algorithm.heuristic_gain: expected one of {', '.join(GAINS)}, "
                             f"got {self.heuristic_gain!r}")
        if self.batch_expansions < 1:
            raise InputError(f"algorithm.batch_expansions: expected >= 1, "
                             f"got {self.batch_expansions}")

    def constants(self, rule_set: str) -> tuple[float, float, float]:
        """``k1, k2, k3``: each given one, else the paper's for ``function`` and ``rule_set``."""
        paper = PAPER_CONSTANTS[(self.function, rule_set)]
        k1, k2, k3 = (v if v >= 0 else s for v, s in zip((self.k1, self.k2, self.k3), paper,
                                                          strict=True))
        return k1, k2, k3
