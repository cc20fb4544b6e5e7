"""Choosing the exported policy on fixed validation episodes (``problem.validate_every``).

A policy search scores its centre every generation on ``eval_episodes`` fresh episodes, and
the run keeps the centre with the best such score. On noisy tasks (perturbed worlds, pushes,
random commands) that is the best of hundreds of noisy draws: the winner's curse picks a
lucky centre, not a good one (docs/policies.md measures it). With ``validate_every = k > 0``
the centre of every k-th generation (0, k, 2k, ...) also plays ``validate_episodes`` episodes
of fixed seeds, :data:`VALID_SEED_BASE` + 0, 1, ...: the same worlds, commands and pushes for
every candidate (common random numbers), apart from the training seeds (below 2^31), the gym
replay's (2^31 + s) and the compare commands' (2^40 + ...). The run exports the candidate
with the best mean validation return.

The validation rows travel in the generation's one evaluation batch (every evaluator runs
them) and draw no random numbers, so the search itself (its centres, the normaliser, the
history's other columns) is bit for bit the same with validation on or off; only the choice
of the exported centre and the run's best differ.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evomotion.core.checks import check_number

#: the first validation seed (exact in a float64 row; see the module docstring)
VALID_SEED_BASE = 2**36
MAX_VALIDATE_EPISODES = 1024


@dataclass(frozen=True)
class Validated:
    """The best validated centre so far (``cost`` inf: none yet)."""

    x: np.ndarray
    cost: float  # minus its mean return over the validation episodes
    obs_mean: np.ndarray  # the normaliser it was evaluated with
    obs_std: np.ndarray
    generation: int = -1


def no_validated(x: np.ndarray, obs_dim: int) -> Validated:
    return Validated(np.asarray(x, float).copy(), float("inf"), np.zeros(obs_dim),
                     np.ones(obs_dim))


def due(generation: int, every: int) -> bool:
    """Whether generation ``generation``'s centre is validated."""
    return every > 0 and generation % every == 0


def validation_seeds(episodes: int) -> np.ndarray:
    return VALID_SEED_BASE + np.arange(int(episodes), dtype=np.int64)


def validation_cost(returns: np.ndarray) -> float:
    """Minus the mean return of one centre's validation episodes; inf where any is not
    finite (a failed or diverged episode: never exported over a finite one)."""
    r = np.asarray(returns, float)
    return float(-r.mean()) if r.size and np.isfinite(r).all() else float("inf")


def check_validation(every: int, episodes: int) -> None:
    """``problem.validate_every`` (0 off, else generations) and ``problem.validate_episodes``."""
    check_number("problem.validate_every", every, lo=0, hi=10**6, integer=True)
    check_number("problem.validate_episodes", episodes, lo=1, hi=MAX_VALIDATE_EPISODES,
                 integer=True)
