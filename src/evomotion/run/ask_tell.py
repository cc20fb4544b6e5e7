"""The generic driver: any registered ask/tell optimizer on any problem.

One step is one generation: ``ask`` -> evaluate -> ``tell``, repeated while the optimizer says
its generation is not done (the cellular GA's asynchronous sweeps span several waves).
A problem may supply its own initial population (``initial_population(n, rng)``) and its own
mutation (``mutate(x, rng, rate)``, for example the validity-keeping path mutation of
grid-path); both are passed to the optimizer, so no study needs a loop of its own.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from evomotion.core.algorithms import ALGORITHMS
from evomotion.core.optimizer import Optimizer
from evomotion.core.problem import Problem
from evomotion.core.qd import QDOptimizer
from evomotion.core.registry import lookup
from evomotion.errors import InputError
from evomotion.run.contracts import HasMeasures, OwnInitialPopulation, OwnMutation
from evomotion.run.driver import Driver, Evaluate, StepReport


def make_optimizer(problem: Problem, algorithm_cfg: Any) -> Optimizer:
    """The optimizer registered as ``algorithm_cfg.name``, with the problem's hooks (its
    mutation; its measure spec for a quality-diversity optimizer)."""
    _, factory = lookup(ALGORITHMS, "algorithm", algorithm_cfg.name)
    kwargs: dict[str, Any] = {}
    if isinstance(problem, OwnMutation):
        kwargs["mutate"] = problem.mutate
    if getattr(algorithm_cfg, "needs_measures", False):
        spec = problem.measure_spec if isinstance(problem, HasMeasures) else None
        if spec is None:
            raise InputError(f"algorithm.name: {algorithm_cfg.name!r} is a quality-diversity "
                             "optimizer and needs a problem with measures (behaviour "
                             "descriptors); this study's problem has none")
        kwargs["measures"] = spec
    return factory(problem.genome, algorithm_cfg, **kwargs)


def scalar_metrics(ev_metrics: dict[str, np.ndarray], i: int) -> dict[str, float]:
    """The scalar metrics of individual ``i`` (vector-valued metrics are left out)."""
    out = {}
    for k, v in ev_metrics.items():
        vi = np.asarray(v[i])
        if vi.ndim == 0 or vi.size == 1:
            out[k] = float(vi.ravel()[0])
    return out


class AskTellDriver(Driver):
    """Steps ``optimizer`` on ``problem``: one step per generation."""

    def __init__(self, problem: Problem, optimizer: Optimizer) -> None:
        self.problem = problem
        self.opt = optimizer
        self.sense = problem.sense
        self.extra_columns = tuple(optimizer.extra_columns)

    def init(self, rng: np.random.Generator) -> Any:
        if not isinstance(self.problem, OwnInitialPopulation):
            return self.opt.init(rng)
        n: Any = getattr(getattr(self.opt, "cfg", None), "pop_size", None)
        return self.opt.init(rng, self.problem.initial_population(n, rng))

    def state_type(self) -> type:
        return type(self.opt.init(np.random.default_rng(0)))

    def step(self, state: Any, rng: np.random.Generator,
             evaluate: Evaluate) -> tuple[Any, StepReport]:
        n = nfail = 0
        errors: list[str] = []
        best_metrics = None
        opt, sense = self.opt, self.sense
        while True:  # one pass per batch (a cellular-GA sweep has many): keep it lean
            genomes, state = opt.ask(state, rng)
            ev = evaluate(genomes)  # sanitized: non-finite fitness is already the worst
            # sanitized, so only the sign remains of to_cost (tell maps any non-finite to inf)
            cost = ev.fitness if sense == "min" else -ev.fitness
            prev_best = state.best_cost
            state = opt.tell(state, genomes, cost, rng, measures=ev.measures) \
                if opt.needs_measures else opt.tell(state, genomes, cost, rng)
            n += len(genomes)
            if ev.failed is not None and ev.failed.any():
                nfail += int(ev.failed.sum())
            if ev.errors:
                errors.extend(ev.errors)
            if state.best_cost < prev_best:
                best_metrics = scalar_metrics(ev.metrics, int(cost.argmin()))
            if opt.generation_done(state):
                break
        pop, pcost = self.opt.population(state)
        extras = opt.qd_stats(state) if self.extra_columns else {}
        return state, StepReport(n, np.asarray(pcost, float), pop, nfail, errors, best_metrics,
                                 extras)

    def check_state(self, state: Any) -> None:
        d = self.problem.genome.dim
        pop, cost = self.opt.population(state)
        pop, cost = np.asarray(pop), np.asarray(cost)
        n = self.opt.expected_population()
        if pop.ndim != 2 or pop.shape[1] != d or (n is not None and pop.shape[0] != n):
            raise ValueError(f"population of shape {pop.shape}, expected "
                             f"({n if n is not None else 'n'}, {d})")
        if cost.shape != (pop.shape[0],):
            raise ValueError(f"{cost.shape} costs for {pop.shape[0]} genomes")
        if not np.isfinite(pop).all():
            raise ValueError("non-finite genes in the population")
        bx, _ = self.opt.best(state)
        if np.shape(bx) != (d,):
            raise ValueError(f"best genome of shape {np.shape(bx)}, expected ({d},)")
        self.opt.check_next_step(state)

    def best(self, state: Any) -> tuple[np.ndarray, float]:
        return self.opt.best(state)

    def archive_view(self, state: Any) -> tuple[Any, Any, tuple[str, ...]] | None:
        if not isinstance(self.opt, QDOptimizer):
            return None
        return self.opt.spec, self.opt.result_archive(state), self.opt.measure_spec.names

    def stop(self, state: Any) -> str | None:
        return self.opt.stop(state)
