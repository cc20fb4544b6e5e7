from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from evomotion.core.ga import GA, GAConfig, GAState
from evomotion.core.problem import GenomeSpec
from evomotion.core.state import state_from_arrays, state_to_arrays

G = GenomeSpec.box(10, -5.0, 5.0)


def _run(cfg, gens=40, seed=0):
    ga = GA(G, cfg)
    rng = np.random.default_rng(seed)
    s = ga.init(rng)
    for _ in range(gens):
        x, s = ga.ask(s, rng)
        assert np.all((x >= G.lower) & (x <= G.upper))
        s = ga.tell(s, x, (x**2).sum(1), rng)
    return ga, s


@pytest.mark.parametrize("crossover", ["one_point", "two_point", "uniform", "arithmetic_whole",
                                       "arithmetic_single", "geometric", "linear", "blx_alpha",
                                       "sbx", "beta_blend"])
@pytest.mark.parametrize("replacement", ["generational", "plus"])
def test_ga_improves_with_every_crossover(crossover, replacement):
    cfg = GAConfig(pop_size=30, crossover=crossover, replacement=replacement)
    ga, s = _run(cfg)
    assert s.pop.shape == (30, 10)
    assert ga.best(s)[1] < 5.0  # random sampling in [-5, 5]^10 gives about 83


def test_elitism_keeps_best_monotone():
    cfg = GAConfig(pop_size=20, selection="roulette", elitism=0.1)
    ga = GA(G, cfg)
    rng = np.random.default_rng(3)
    s = ga.init(rng)
    best = []
    for _ in range(15):
        x, s = ga.ask(s, rng)
        s = ga.tell(s, x, (x**2).sum(1), rng)
        best.append(s.cost.min())
    assert all(b1 >= b2 for b1, b2 in zip(best, best[1:], strict=False))


def test_linear_crossover_asks_three_children_per_pair():
    ga = GA(G, GAConfig(pop_size=10, crossover="linear", elitism=0))
    rng = np.random.default_rng(0)
    s = ga.init(rng)
    x, s = ga.ask(s, rng)
    s = ga.tell(s, x, (x**2).sum(1), rng)
    kids, s = ga.ask(s, rng)
    assert kids.shape == (15, 10)
    s = ga.tell(s, kids, (kids**2).sum(1), rng)
    assert s.pop.shape == (10, 10)


def test_inf_cost_never_becomes_best():
    ga = GA(G, GAConfig(pop_size=10))
    rng = np.random.default_rng(0)
    s = ga.init(rng)
    x, s = ga.ask(s, rng)
    cost = (x**2).sum(1)
    cost[0] = np.nan
    s = ga.tell(s, x, cost, rng)
    assert np.isinf(s.cost[0]) and np.isfinite(ga.best(s)[1])


def test_state_round_trip_and_determinism():
    _, s1 = _run(GAConfig(pop_size=16), gens=10, seed=7)
    _, s2 = _run(GAConfig(pop_size=16), gens=10, seed=7)
    np.testing.assert_array_equal(s1.pop, s2.pop)
    arrays, meta = state_to_arrays(s1)
    back = state_from_arrays(GAState, arrays, meta)
    for f in dataclasses.fields(GAState):
        np.testing.assert_array_equal(getattr(back, f.name), getattr(s1, f.name))


@pytest.mark.parametrize("bad", [dict(pop_size=1), dict(crossover_rate=2.0),
                                 dict(mutation="nope"), dict(elitism=-1)])
def test_invalid_config_rejected(bad):
    with pytest.raises((ValueError, KeyError)):
        GA(G, GAConfig(**bad))


def _path_like_mutation(x, rng, rate):
    """A problem mutation drawing from ``rng`` (like the grid-path one)."""
    u = rng.random(x.shape[0])
    x = np.array(x, dtype=float)
    rows = u < rate
    x[rows, 0] += rng.standard_normal(int(rows.sum()))
    return x


@pytest.mark.parametrize("cfg", [GAConfig(pop_size=12),
                                 GAConfig(pop_size=11, crossover="linear", replacement="plus"),
                                 GAConfig(pop_size=10, mutation="perturb_k", elitism=0)])
def test_mutate_hook_equals_rate_zero_ga_with_outer_mutation(cfg):
    """GA(mutate=m) is, random stream included, the grid-path study's former loop: a GA with
    mutation_rate=0 whose asked children (not the initial population) are mutated by m."""
    pop0 = G.sample(np.random.default_rng(9), cfg.pop_size)
    hooked = GA(G, cfg, mutate=_path_like_mutation)
    outer = GA(G, dataclasses.replace(cfg, mutation_rate=0.0))
    ra, rb = np.random.default_rng(4), np.random.default_rng(4)
    sa, sb = hooked.init(ra, pop0), outer.init(rb, pop0)
    for gen in range(12):
        xa, sa = hooked.ask(sa, ra)
        xb, sb = outer.ask(sb, rb)
        if gen > 0:
            xb = _path_like_mutation(xb, rb, cfg.mutation_rate)
        assert np.array_equal(xa, xb)
        sa, sb = hooked.tell(sa, xa, (xa**2).sum(1), ra), outer.tell(sb, xb, (xb**2).sum(1), rb)
    assert np.array_equal(sa.pop, sb.pop) and hooked.best(sa)[1] == outer.best(sb)[1]
