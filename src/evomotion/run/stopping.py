"""The stop rules shared by every study: limits, target, stagnation, the method's own."""

from __future__ import annotations

from typing import Any

from evomotion.run.config import Config
from evomotion.run.counters import Counters


def stop_reason(driver: Any, state: Any, config: Config, c: Counters, best_cost: float,
                mean_cost: float, sgn: float) -> str | None:
    """The first rule that fires (costs are minimised; ``fitness = sgn * cost``). ``c`` holds
    the run counters; its stagnation history is updated here."""
    rc = config.run
    limit = limit_reached(config, c, best_cost, sgn)
    if limit is not None:
        return limit
    if rc.stagnation_generations:
        n = rc.stagnation_generations
        c.hist_best = (c.hist_best + [best_cost])[-(n + 1):]
        c.hist_mean = (c.hist_mean + [mean_cost])[-(n + 1):]
        if len(c.hist_best) == n + 1:
            db = _gain(c.hist_best[0], c.hist_best[-1])
            dm = _gain(c.hist_mean[0], c.hist_mean[-1])
            if db < rc.stagnation_eps and dm < rc.stagnation_eps:
                return "stagnation"
    return driver.stop(state)


def limit_reached(config: Config, c: Counters, best_cost: float, sgn: float) -> str | None:
    """``generations``, ``max_evaluations``, ``target`` or ``wall_seconds``, else None."""
    rc = config.run
    if c.generation >= rc.generations:
        return "generations"
    if rc.max_evaluations and c.evaluations >= rc.max_evaluations:
        return "max_evaluations"
    if rc.target is not None and best_cost <= sgn * rc.target:
        return "target"
    if rc.wall_seconds and c.wall_s >= rc.wall_seconds:
        return "wall_seconds"
    return None


def _gain(before: float, after: float) -> float:
    """Improvement of a minimised value (0 when nothing changed, also for inf -> inf)."""
    return 0.0 if before == after else before - after
