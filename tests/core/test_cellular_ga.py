"""Cellular GA: neighbourhoods, exact asynchronous waves, update policies, replacement."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.core.cellular_ga import (
    UPDATE_POLICIES,
    CellularGA,
    CGAConfig,
    CGAState,
    roulette_rows,
    update_waves,
)
from evomotion.core.neighbourhoods import NEIGHBOURHOODS, grid_shape, neighbour_table
from evomotion.core.problem import GenomeSpec
from evomotion.core.registry import UnknownNameError
from evomotion.core.state import state_from_arrays, state_to_arrays

SIZES = {"L5": 5, "C9": 9, "L9": 9, "C13": 13, "Margolus": 4}


@pytest.mark.parametrize("name", NEIGHBOURHOODS)
def test_neighbourhood_shape_self_first_and_symmetric(name):
    t = neighbour_table(name, 8, 10, generation=1)
    assert t.shape == (80, SIZES[name])
    assert np.array_equal(t[:, 0], np.arange(80))
    assert all(len(set(row)) == SIZES[name] for row in t.tolist())  # distinct on 8x10
    pairs = {(a, b) for a, row in enumerate(t.tolist()) for b in row}
    assert all((b, a) in pairs for a, b in pairs)


def test_l5_is_von_neumann_on_torus():
    t = neighbour_table("L5", 4, 5)
    assert sorted(t[0].tolist()) == sorted([0, 15, 5, 4, 1])  # up wraps, left wraps


def test_margolus_blocks_shift_with_generation_parity():
    even = neighbour_table("Margolus", 4, 4, 0)
    odd = neighbour_table("Margolus", 4, 4, 1)
    assert sorted(even[0].tolist()) == [0, 1, 4, 5]
    assert sorted(odd[0].tolist()) == [0, 3, 12, 15]  # block straddling the wrap
    assert sorted(odd[5].tolist()) == [5, 6, 9, 10]
    blocks = {tuple(sorted(r)) for r in even.tolist()}
    assert len(blocks) == 4 and sorted(sum(blocks, ())) == list(range(16))


def test_grid_shape_and_unknown_names():
    assert grid_shape(100) == (10, 10) and grid_shape(225) == (15, 15)
    assert grid_shape(12) == (3, 4) and grid_shape(12, rows=2) == (2, 6)
    with pytest.raises(ValueError):
        grid_shape(10, rows=3)
    with pytest.raises(UnknownNameError, match="available"):
        neighbour_table("hex", 4, 4)
    with pytest.raises(UnknownNameError, match="update policy"):
        CGAConfig(update="random").validate()


@settings(max_examples=40, deadline=None)
@given(st.sampled_from(NEIGHBOURHOODS), st.integers(0, 2**31), st.booleans())
def test_waves_reproduce_sequential_order(name, seed, repeats):
    rng = np.random.default_rng(seed)
    table = neighbour_table(name, 6, 6, seed % 2)
    seq = rng.integers(0, 36, 36) if repeats else rng.permutation(36)
    waves = update_waves(seq, table)
    for k in range(len(seq)):
        for j in range(k):
            if seq[j] in table[seq[k]]:  # k reads j (or is the same cell): j first
                assert waves[j] < waves[k]
    for w in np.unique(waves):  # cells of one wave never read each other
        cells = seq[waves == w]
        assert len(set(cells.tolist())) == len(cells)
        for c in cells:
            assert not (set(table[c, 1:].tolist()) & set(cells.tolist()) - {c})


def _run(cfg: CGAConfig, generations: int, seed: int = 0, pop=None, fn=None):
    """The initial evaluation and ``generations`` sweeps (``state.generation`` counts both)."""
    g = GenomeSpec.box(1 if pop is not None else 6, -5.0, 5.0)
    opt = CellularGA(g, cfg)
    rng = np.random.default_rng(seed)
    state = opt.init(rng, pop)
    fn = fn or (lambda x: (x ** 2).sum(1))
    tells = 0
    while state.generation < generations + 1:
        x, state = opt.ask(state, rng)
        state = opt.tell(state, x, fn(x), rng)
        tells += 1
    return opt, state, tells


def _takeover(update: str, seed: int) -> int:
    pop = np.ones((100, 1))
    pop[0] = 0.0  # one best individual; copies spread only by mating
    cfg = CGAConfig(pop_size=100, update=update, neighbourhood="L5", crossover_rate=1.0,
                    mutation_rate=0.0, mate_selection="best", replacement="if_better")
    _, state, _ = _run(cfg, 1, seed, pop=pop, fn=lambda x: x[:, 0])
    return int((state.pop[:, 0] == 0.0).sum())


def test_synchronous_spreads_one_step_line_sweep_further():
    sync = [_takeover("synchronous", s) for s in range(10)]
    sweep = [_takeover("line_sweep", s) for s in range(10)]
    assert max(sync) <= 5  # only the 4 Von Neumann neighbours can copy it in one generation
    assert np.mean(sweep) > 6  # the sweep carries it along rows and down columns


@pytest.mark.parametrize("update", UPDATE_POLICIES)
@pytest.mark.parametrize("name", NEIGHBOURHOODS)
def test_every_policy_and_neighbourhood_improves_monotonically(update, name):
    cfg = CGAConfig(pop_size=36, neighbourhood=name, update=update, mutation="gaussian",
                    mutation_rate=0.5)
    opt, state, tells = _run(cfg, 1)
    start = state.cost.copy()
    x0 = state.pop.copy()
    rng = np.random.default_rng(1)
    while state.generation < 16:
        x, state = opt.ask(state, rng)
        state = opt.tell(state, x, (x ** 2).sum(1), rng)
    assert np.all(state.cost <= start)  # replace-if-better never worsens a cell
    assert state.cost.mean() < start.mean()
    assert not np.array_equal(state.pop, x0)
    assert opt.best(state)[1] == state.cost.min()


def test_sweep_orders():
    cfg = dict(pop_size=16, neighbourhood="L5", mutation_rate=0.0)
    fixed, st_f, _ = _run(CGAConfig(update="fixed_random_sweep", **cfg), 1)
    order = st_f.sequence.copy()
    _, st_f2, _ = _run(CGAConfig(update="fixed_random_sweep", **cfg), 3)
    assert np.array_equal(st_f2.sequence, order) and sorted(order) == list(range(16))
    _, st_n, _ = _run(CGAConfig(update="new_random_sweep", **cfg), 1, seed=3)
    first = st_n.sequence.copy()
    assert sorted(first) == list(range(16))
    _, st_u, _ = _run(CGAConfig(update="uniform_choice", **cfg), 1, seed=3)
    assert len(st_u.sequence) == 16 and len(set(st_u.sequence.tolist())) < 16
    _, st_l, _ = _run(CGAConfig(update="line_sweep", **cfg), 1)
    assert np.array_equal(st_l.sequence, np.arange(16))


def test_tells_per_generation():
    _, _, sync = _run(CGAConfig(pop_size=100, update="synchronous"), 5)
    _, _, sweep = _run(CGAConfig(pop_size=100, update="line_sweep"), 5)
    assert sync == 1 + 5  # the initial evaluation, then one wave per generation
    assert sweep == 1 + 5 * 19  # row-major sweep of a 10x10 torus with L5: 19 waves


def test_mutate_hook_replaces_registry_mutation():
    calls = []

    def hook(x, rng, rate):
        calls.append((x.shape, rate))
        return x + 0.0

    g = GenomeSpec.box(3, 0.0, 1.0)
    opt = CellularGA(g, CGAConfig(pop_size=9, update="synchronous", mutation_rate=0.25),
                     mutate=hook)
    rng = np.random.default_rng(0)
    state = opt.init(rng)
    x, state = opt.ask(state, rng)
    state = opt.tell(state, x, x.sum(1), rng)
    opt.ask(state, rng)
    assert calls == [((9, 3), 0.25)]


def test_roulette_rows_weights():
    rng = np.random.default_rng(0)
    cost = np.tile([1.0, 2.0, np.inf, 3.0], (20000, 1))
    j = roulette_rows(cost, rng)
    freq = np.bincount(j, minlength=4) / j.size
    assert freq[2] == 0.0 and freq[0] > freq[1] > freq[3] > 0
    flat = roulette_rows(np.full((4000, 3), np.inf), rng)
    assert set(flat.tolist()) == {0, 1, 2}


def _roulette_reference(cost, rng):
    """The documented weights, row by row in plain Python (finite costs)."""
    u = rng.random((cost.shape[0], 1))[:, 0]
    out = []
    for row, ui in zip(cost.tolist(), u.tolist(), strict=True):
        hi, lo = max(row), min(row)
        w = [hi - c + (1e-3 * (hi - lo) if hi > lo else 1.0) for c in row]
        cdf = np.cumsum(w)
        out.append(min(int((cdf <= ui * cdf[-1]).sum()), len(row) - 1))
    return np.array(out)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**31), st.integers(1, 9))
def test_roulette_rows_fast_path_matches_reference(seed, k):
    rng = np.random.default_rng(seed)
    cost = rng.choice([0.5, 1.0, 2.0, 7.25], (50, k)) + rng.random((50, k)) * (seed % 2)
    assert np.array_equal(roulette_rows(cost, np.random.default_rng(seed)),
                          _roulette_reference(cost, np.random.default_rng(seed)))


def test_roulette_rows_huge_and_infinite_costs(recwarn):
    """Finite costs whose row sums overflow take the exact path and pick the same columns
    as the plain-Python reference; inf and nan costs raise no numpy warning."""
    cost = np.array([[1e307, 1.7e307, 0.0], [1.6e307, 1e307, 1.7e307]] * 10)
    with np.errstate(over="ignore"):  # the sum of the rows' maxima overflows
        assert np.array_equal(roulette_rows(cost, np.random.default_rng(3)),
                              _roulette_reference(cost, np.random.default_rng(3)))
    j = roulette_rows(np.array([[np.inf, 1.0, np.nan], [np.inf, np.inf, np.inf]]),
                      np.random.default_rng(0))
    assert j[0] == 1 and 0 <= j[1] <= 2
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


@pytest.mark.parametrize("fast", [True, False])
@pytest.mark.parametrize("update", ["line_sweep", "new_random_sweep", "uniform_choice"])
def test_mid_generation_restore_is_exact(update, fast):
    cfg = CGAConfig(pop_size=36, update=update, crossover_rate=0.7, mutation_rate=0.3)
    g = GenomeSpec.box(5, -5.0, 5.0)

    def run(restore_at: int = -1):
        opt = CellularGA(g, cfg)
        opt._fast_one_point = fast
        rng = np.random.default_rng(11)
        state = opt.init(rng)
        for t in range(40):
            if t == restore_at:  # a fresh optimizer from a checkpoint-like copy
                arrays, meta = state_to_arrays(state)
                state = state_from_arrays(CGAState, {k: v.copy() for k, v in arrays.items()},
                                          meta)
                opt = CellularGA(g, cfg)
                opt._fast_one_point = fast
            x, state = opt.ask(state, rng)
            state = opt.tell(state, x, (x ** 2).sum(1), rng)
        return state.pop, state.cost, state.wave, state.generation

    ref = run()
    assert ref[3] >= 2  # several generations, mid-generation end
    got = run(restore_at=17)
    assert all(np.array_equal(a, b) for a, b in zip(got, ref, strict=True))


def _mate_reference(ncost: list[float], u: float, how: str, u2: float) -> int:
    """Mate column in plain Python: the documented roulette weights, or a 2-tournament."""
    k = len(ncost)
    if how == "tournament":
        a, b = int(u * k), int(u2 * k)
        return a if ncost[a] <= ncost[b] else b
    hi, lo = max(ncost), min(ncost)
    cdf, acc = [], 0.0
    for c in ncost:
        acc += hi - c + (1e-3 * (hi - lo) if hi > lo else 1.0)
        cdf.append(acc)
    return min(sum(v <= u * cdf[-1] for v in cdf), k - 1)


def _sequential_generation(opt, pop, cost, state, fn, mutate):
    """One generation updated one cell at a time in sequence order, from ``pop``/``cost``,
    using the uniforms the vectorised optimizer drew (column = position in wave order)."""
    cfg, d = opt.cfg, pop.shape[1]
    pop, cost = [list(r) for r in pop.tolist()], cost.tolist()
    order = np.argsort(state.waves, kind="stable")
    col = np.empty_like(order)
    col[order] = np.arange(len(order))
    table = opt.table(state.generation - 1).tolist()  # this sweep's table
    u = state.draws.tolist()
    for p, c in enumerate(state.sequence.tolist()):
        k = int(col[p])
        nbr = table[c][1:]
        mate = pop[nbr[_mate_reference([cost[j] for j in nbr], u[0][k], cfg.mate_selection,
                                       u[1][k])]]
        child = list(pop[c])
        if u[4][k] < cfg.crossover_rate:
            cut = 1 + int(u[2][k] * (d - 1))
            child = child[:cut] + mate[cut:] if u[3][k] < 0.5 else mate[:cut] + child[cut:]
        x = mutate(np.array([child]), None, cfg.mutation_rate)
        f = float(fn(x)[0])
        if f < cost[c]:
            pop[c], cost[c] = x[0].tolist(), f
    return np.array(pop), np.array(cost)


@settings(max_examples=25, deadline=None)
@given(st.sampled_from(UPDATE_POLICIES[1:]), st.sampled_from(NEIGHBOURHOODS),
       st.sampled_from(["roulette", "tournament"]), st.integers(0, 2**31))
def test_waves_equal_one_cell_at_a_time_updating(update, name, mate, seed):
    """The vectorised waves give exactly the sequential (asynchronous) update."""
    def mutate(x, rng, rate):  # deterministic, so the reference can repeat it per cell
        return np.clip(0.9 * x + 0.05, -5.0, 5.0)

    def fn(x):
        return ((x - 0.3) ** 2).sum(1)

    cfg = CGAConfig(pop_size=36, update=update, neighbourhood=name, mate_selection=mate,
                    crossover_rate=0.8, mutation_rate=0.5)
    opt = CellularGA(GenomeSpec.box(4, -5.0, 5.0), cfg, mutate=mutate)
    rng = np.random.default_rng(seed)
    state = opt.init(rng)
    x, state = opt.ask(state, rng)
    state = opt.tell(state, x, fn(x), rng)
    for _ in range(2):
        pop0, cost0, first = state.pop.copy(), state.cost.copy(), True
        while first or not opt.end_of_generation(state):
            x, state = opt.ask(state, rng)
            if first:
                ref = _sequential_generation(opt, pop0, cost0, state, fn, mutate)
                first = False
            state = opt.tell(state, x, fn(x), rng)
        assert np.array_equal(state.pop, ref[0]) and np.array_equal(state.cost, ref[1])
