"""Every registered optimizer honours the ask/tell contract of :mod:`evomotion.core.optimizer`.

Parametrised over ``ALGORITHMS`` with no exemptions: shapes; ``ask``/``tell`` never mutate
the state passed in; the base's best-so-far and generation bookkeeping; checkpoint round trip
through ``state_to_arrays``/``state_from_arrays`` with bit-identical continuation; the
uniform factory signature with the ``mutate`` hook either used or rejected with ValueError.
Every optimizer is told the measures (behaviour descriptors) of what it asked for; the
quality-diversity ones (``needs_measures``) get the measure spec from their factory and use
them, the others ignore them.
"""

from __future__ import annotations

import copy
import dataclasses

import numpy as np
import pytest

from evomotion.core.algorithms import ALGORITHMS
from evomotion.core.optimizer import Optimizer
from evomotion.core.problem import GenomeSpec, MeasureSpec
from evomotion.core.state import state_from_arrays, state_to_arrays

GENOME = GenomeSpec.box(4, -2.0, 3.0)
MEASURES = MeasureSpec(("x0", "x1"), GENOME.lower[:2], GENOME.upper[:2], (5, 5))
NAMES = sorted(ALGORITHMS)


def make(name: str, **kw) -> tuple[Optimizer, object]:
    cfg_cls, factory = ALGORITHMS[name]
    cfg = cfg_cls(pop_size=16)
    if getattr(cfg, "needs_measures", False):
        kw["measures"] = MEASURES
    return factory(GENOME, cfg, **kw), cfg


def measures_of(x: np.ndarray) -> np.ndarray:
    return x[:, :2].copy()


def cost_fn(x: np.ndarray) -> np.ndarray:
    return np.round(((x - 0.5) ** 2).sum(1), 1)  # rounded: ties between distinct genomes


def assert_same_state(a, b) -> None:
    arrays_a, meta_a = state_to_arrays(a)
    arrays_b, meta_b = state_to_arrays(b)
    assert meta_a == meta_b
    assert arrays_a.keys() == arrays_b.keys()
    for k in arrays_a:
        assert arrays_a[k].dtype == arrays_b[k].dtype, k
        np.testing.assert_array_equal(arrays_a[k], arrays_b[k], err_msg=k)


def step(opt: Optimizer, state, rng, fn=cost_fn):
    """One ask/tell pair, checking that neither mutates the state it was given."""
    before = copy.deepcopy(state)
    x, asked = opt.ask(state, rng)
    assert_same_state(state, before)
    assert x.ndim == 2 and x.shape[1] == GENOME.dim and x.shape[0] >= 1
    assert np.all(np.isfinite(x))
    asked_copy = copy.deepcopy(asked)
    cost = fn(x)
    new = opt.tell(asked, x, cost, rng, measures=measures_of(x))
    assert_same_state(asked, asked_copy)
    assert type(new) is type(state)
    return x, cost, asked, new


@pytest.mark.parametrize("name", NAMES)
def test_factory_signature_and_initial_state(name):
    opt, cfg = make(name)
    assert isinstance(opt, Optimizer)
    state = opt.init(np.random.default_rng(0))
    assert dataclasses.is_dataclass(state)
    for f in ("best_x", "best_cost", "generation"):
        assert hasattr(state, f)
    assert state.generation == 0 and state.best_cost == np.inf
    assert opt.best(state)[1] == np.inf and opt.stop(state) is None


@pytest.mark.parametrize("name", NAMES)
def test_shapes_immutability_and_bookkeeping(name):
    opt, _ = make(name)
    rng = np.random.default_rng(1)
    state = opt.init(rng)
    best, tells = np.inf, 0
    while state.generation < 6:
        if tells == 2:  # a failed evaluation never becomes the best
            x, cost, asked, new = step(opt, state, rng,
                                       lambda x: np.r_[np.nan, cost_fn(x)[1:]])
            cost = np.where(np.isnan(cost), np.inf, cost)
        else:
            x, cost, asked, new = step(opt, state, rng)
        tells += 1
        i = int(np.argmin(cost))
        if cost[i] < best:
            best = cost[i]
            np.testing.assert_array_equal(opt.best(new)[0], x[i])
        assert opt.best(new)[1] == best == new.best_cost
        done = opt.generation_done(new)
        assert opt.end_of_generation(new) == done
        assert new.generation == asked.generation + (1 if done else 0)
        pop, pcost = opt.population(new)
        assert pop.ndim == 2 and pop.shape[1] == GENOME.dim and pcost.shape == (len(pop),)
        state = new
    assert tells >= 6 and np.isfinite(best)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("at", [1, 4, 9])
def test_round_trip_continues_bit_identically(name, at):
    opt, _ = make(name)
    rng = np.random.default_rng(2)
    state = opt.init(rng)
    for _ in range(at):
        _, _, _, state = step(opt, state, rng)
    arrays, meta = state_to_arrays(state)
    back = state_from_arrays(type(state), {k: np.array(v) for k, v in arrays.items()},
                             copy.deepcopy(meta))
    assert_same_state(back, state)
    rng_b = np.random.default_rng()
    rng_b.bit_generator.state = rng.bit_generator.state
    opt_b, _ = make(name)  # a fresh optimizer: everything of the run is in the state
    for _ in range(12):
        xa, _, _, state = step(opt, state, rng)
        xb, _, _, back = step(opt_b, back, rng_b)
        assert np.array_equal(xa, xb)
    assert_same_state(back, state)


@pytest.mark.parametrize("name", NAMES)
def test_init_accepts_a_population(name):
    opt, cfg = make(name)
    pop = GENOME.sample(np.random.default_rng(3), cfg.pop_size) * 0.5
    rng = np.random.default_rng(4)
    state = opt.init(rng, pop)
    x, _, _, state = step(opt, state, rng)
    assert x.shape[1] == GENOME.dim
    with pytest.raises(ValueError):
        opt.init(rng, np.zeros((cfg.pop_size, GENOME.dim + 1)))


@pytest.mark.parametrize("name", NAMES)
def test_mutate_hook_is_used_or_rejected(name):
    mark = GENOME.lower + 0.25 * GENOME.span
    calls = []

    def hook(x, rng, rate):
        assert isinstance(rng, np.random.Generator)
        calls.append((x.shape, rate))
        return np.broadcast_to(mark, x.shape).copy()

    try:
        opt, cfg = make(name, mutate=hook)
    except ValueError as e:  # documented rejection (CMA-ES has no mutation to replace)
        assert "mutate" in str(e)
        return
    rng = np.random.default_rng(5)
    state = opt.init(rng)
    x0, _, _, state = step(opt, state, rng)
    assert not calls  # the initial population is not mutated
    for _ in range(3):
        x, _, _, state = step(opt, state, rng)
        assert np.array_equal(x, np.broadcast_to(mark, x.shape))
    assert calls and all(shape[1] == GENOME.dim and rate == cfg.mutation_rate
                         for shape, rate in calls)
