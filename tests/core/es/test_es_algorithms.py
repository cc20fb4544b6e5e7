"""OpenAI-ES, ARS, PGPE and SNES: they solve a sphere, sample as their papers say, and
honour the box, ``init(population=...)``, ``center`` and their config checks."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.core.algorithms import ALGORITHMS, make_optimizer
from evomotion.core.es.ars import ars_step, top_directions
from evomotion.core.problem import GenomeSpec
from evomotion.errors import InputError

GENOME = GenomeSpec.box(20, -1.0, 1.5)  # centre 0.25 on every gene; optimum at 0
ES = ("openai_es", "ars", "pgpe", "snes")
SOLVE = {"openai_es": dict(pop_size=40, sigma=0.05, learning_rate=0.02, weight_decay=0.0),
         "ars": dict(pop_size=40, step_size=0.01, noise_std=0.02, top_directions=10),
         "pgpe": dict(pop_size=40, max_speed=0.02, stdev_init=0.1),
         "snes": dict(sigma_init=0.3)}


def sphere(x: np.ndarray) -> np.ndarray:
    return (x**2).sum(-1)


@pytest.mark.parametrize("name", ES)
def test_solves_the_sphere(name):
    opt = make_optimizer(name, GENOME, **SOLVE[name])
    rng = np.random.default_rng(0)
    state = opt.init(rng)
    assert sphere(opt.center(state)) == pytest.approx(20 * 0.25**2)
    for _ in range(300):
        x, state = opt.ask(state, rng)
        state = opt.tell(state, x, sphere(x), rng)
        if sphere(opt.center(state)) < 1e-3:
            break
    assert sphere(opt.center(state)) < 1e-3, state.generation
    assert state.generation < 300


@pytest.mark.parametrize("name", ["openai_es", "ars", "pgpe"])
def test_pairs_are_mirrored_inside_the_bounds(name):
    genome = GenomeSpec.box(6, -100.0, 100.0)
    opt = make_optimizer(name, genome, pop_size=10)
    rng = np.random.default_rng(1)
    state = opt.init(rng, np.full((1, 6), 0.5))
    x, _ = opt.ask(state, rng)
    np.testing.assert_allclose(x[:5] + x[5:], 1.0, atol=1e-12)  # c + p and c - p
    assert np.all(x[:5] != x[5:])


@pytest.mark.parametrize("name", ES)
def test_asked_genomes_and_centre_stay_in_the_bounds(name):
    genome = GenomeSpec.box(5, 0.0, 0.01)  # far narrower than the noise
    opt = make_optimizer(name, genome, pop_size=8)
    rng = np.random.default_rng(2)
    state = opt.init(rng)
    for _ in range(5):
        x, state = opt.ask(state, rng)
        assert np.all(x >= 0.0) and np.all(x <= 0.01)
        state = opt.tell(state, x, -x.sum(1), rng)
        c = opt.center(state)
        assert np.all(c >= 0.0) and np.all(c <= 0.01)


@pytest.mark.parametrize("name", ES)
def test_init_population_row_0_is_the_centre(name):
    opt = make_optimizer(name, GENOME, pop_size=8)
    pop = np.r_[np.full((1, 20), 0.7), np.full((3, 20), -0.9)]
    state = opt.init(np.random.default_rng(3), pop)
    np.testing.assert_array_equal(opt.center(state), np.full(20, 0.7))
    pop[0, 0] = 9.0  # clipped into the bounds
    assert opt.center(opt.init(np.random.default_rng(3), pop))[0] == 1.5
    with pytest.raises(ValueError):
        opt.init(np.random.default_rng(3), np.zeros((0, 20)))


def test_unbounded_genes_start_at_zero_or_the_finite_bound():
    genome = GenomeSpec(np.array([-np.inf, 2.0, -np.inf]), np.array([np.inf, np.inf, -1.0]))
    opt = make_optimizer("openai_es", genome, pop_size=4)
    np.testing.assert_array_equal(opt.center(opt.init(np.random.default_rng(0))),
                                  [0.0, 2.0, -1.0])


def test_ars_top_b_picks_the_right_directions():
    r_plus = np.array([1.0, 5.0, 2.0, 0.0])
    r_minus = np.array([4.0, 0.0, 2.5, 3.0])
    # max(r+, r-) = 4, 5, 2.5, 3 -> directions 1, 0, 3, 2
    assert top_directions(r_plus, r_minus, 2).tolist() == [1, 0]
    assert top_directions(r_plus, r_minus, 4).tolist() == [1, 0, 3, 2]
    assert top_directions(np.ones(3), np.ones(3), 2).tolist() == [0, 1]  # ties: lower first
    nu_delta = np.eye(4) * 0.1  # ν = 0.1: δ_k is the k-th unit vector
    step = ars_step(r_plus, r_minus, nu_delta, 2, step_size=0.5, noise_std=0.1)
    sigma_r = np.std([5.0, 1.0, 0.0, 4.0])  # the 2b rewards of directions 1 and 0
    want = 0.5 / (2 * sigma_r) * np.array([1.0 - 4.0, 5.0 - 0.0, 0.0, 0.0])
    np.testing.assert_allclose(step, want)


def test_ars_uses_only_the_top_directions_and_survives_failures():
    genome = GenomeSpec.box(3, -10.0, 10.0)
    opt = make_optimizer("ars", genome, pop_size=6, top_directions=1, noise_std=0.1)
    rng = np.random.default_rng(4)
    state = opt.init(rng)
    x, state = opt.ask(state, rng)
    cost = np.array([0.0, 5.0, 5.0, 1.0, 5.0, np.inf])  # direction 0 is the best
    new = opt.tell(state, x, cost, rng)
    step = new.center - state.center
    d0 = (x[0] - x[3]) / 2
    np.testing.assert_allclose(step / np.linalg.norm(step), d0 / np.linalg.norm(d0))
    allfail = opt.tell(state, x, np.full(6, np.inf), rng)
    np.testing.assert_array_equal(allfail.center, state.center)


def test_snes_defaults_follow_the_paper():
    genome = GenomeSpec.box(1000, -1.0, 1.0)
    opt = make_optimizer("snes", genome)
    assert opt.expected_population() == 4 + int(np.floor(3 * np.log(1000))) == 24
    assert opt.eta_sigma == pytest.approx((3 + np.log(1000)) / (5 * np.sqrt(1000)))


@pytest.mark.parametrize("name, bad", [
    ("openai_es", dict(pop_size=7)), ("openai_es", dict(sigma=0.0)),
    ("openai_es", dict(beta1=1.0)), ("ars", dict(pop_size=8, top_directions=5)),
    ("ars", dict(step_size=-1.0)), ("pgpe", dict(stdev_max_change=1.0)),
    ("pgpe", dict(momentum=1.0)), ("snes", dict(pop_size=1)), ("snes", dict(sigma_init=0.0)),
])
def test_bad_settings_are_one_line_errors(name, bad):
    with pytest.raises(InputError) as e:
        make_optimizer(name, GENOME, **bad)
    assert "\n" not in str(e.value) and "algorithm." in str(e.value)


def test_registry_names_and_the_unknown_name_message():
    assert {"openai_es", "ars", "pgpe", "snes"} <= set(ALGORITHMS)
    with pytest.raises(InputError, match=r"unknown algorithm 'es'; available: .*openai_es"):
        make_optimizer("es", GENOME)


@pytest.mark.parametrize("name", ES)
def test_center_is_the_distribution_mean_and_base_default_is_best(name):
    opt = make_optimizer(name, GENOME, pop_size=8)
    rng = np.random.default_rng(5)
    state = opt.init(rng)
    x, state = opt.ask(state, rng)
    state = opt.tell(state, x, sphere(x), rng)
    np.testing.assert_array_equal(opt.center(state), state.center)
    ga = make_optimizer("ga", GENOME, pop_size=8)
    s = ga.init(rng)
    x, s = ga.ask(s, rng)
    s = ga.tell(s, x, sphere(x), rng)
    np.testing.assert_array_equal(ga.center(s), ga.best(s)[0])
