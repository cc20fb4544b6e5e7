"""CMA-ES: convergence, bounds, restarts, improvements, checkpoint round trip, determinism."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.core.cmaes import CMAES, CMAESConfig, CMAESState, make_cmaes
from evomotion.core.cmaes_params import strategy_params
from evomotion.core.problem import GenomeSpec
from evomotion.core.state import state_from_arrays, state_to_arrays


def sphere(x: np.ndarray) -> np.ndarray:
    return np.sum((x - 1.0) ** 2, axis=1)


def rosenbrock(x: np.ndarray) -> np.ndarray:
    return np.sum(100 * (x[:, 1:] - x[:, :-1] ** 2) ** 2 + (1 - x[:, :-1]) ** 2, axis=1)


def run(f, dim: int, cfg: CMAESConfig, seed: int = 0, max_evals: int = 20000,
        target: float = 1e-10, lower: float = -5.0, upper: float = 5.0):
    opt = CMAES(GenomeSpec.box(dim, lower, upper), cfg)
    rng = np.random.default_rng(seed)
    state = opt.init(rng)
    while state.evaluations < max_evals and state.best_cost > target and not state.done:
        x, state = opt.ask(state, rng)
        state = opt.tell(state, x, f(x), rng)
    return opt, state


def test_strategy_params_match_tutorial_defaults():
    p = strategy_params(10, 10)
    assert p.mu == 5
    assert np.isclose(p.weights[:5].sum(), 1.0)
    assert np.all(p.weights[:5] > 0) and np.all(p.weights[5:] <= 0)
    assert 3.0 < p.mu_eff < 3.3  # 3.17 for lambda = 10
    assert p.c_1 + p.c_mu <= 1.0
    assert np.isclose(p.chi_n, np.sqrt(10) * (1 - 1 / 40 + 1 / 2100))


@pytest.mark.parametrize("cfg", [CMAESConfig(restarts="none"),
                                 CMAESConfig(restarts="none", chaos=True, levy=True)])
def test_sphere_converges(cfg):
    _, s = run(sphere, 10, cfg, max_evals=4000)
    assert s.best_cost < 1e-10
    assert np.allclose(s.best_x, 1.0, atol=1e-4)


def test_rosenbrock_converges():
    _, s = run(rosenbrock, 8, CMAESConfig(), seed=3, max_evals=30000)
    assert s.best_cost < 1e-10


def test_bounds_respected_and_optimum_on_the_edge():
    # optimum at x = 1 lies outside [-5, 0.5]: the bounded optimum is the corner x = 0.5
    opt, s = run(sphere, 5, CMAESConfig(restarts="none"), lower=-5, upper=0.5,
                 max_evals=3000, target=-1)
    x, s = opt.ask(s, np.random.default_rng(1))
    assert np.all(x >= -5) and np.all(x <= 0.5)
    assert np.allclose(s.best_x, 0.5, atol=1e-3)


def test_restart_increases_population_and_reports_reason():
    opt, s = run(sphere, 4, CMAESConfig(restarts="ipop", max_restarts=2), max_evals=50000,
                 target=-1)
    assert s.done and s.restarts == 2
    assert s.lam == opt.lam0 * 4
    assert opt.stop(s) in {"tolfun", "tolx", "noeffectaxis", "noeffectcoord",
                                  "tolstagnation", "conditioncov"}
    assert s.stop_log.count("@") == 3
    assert opt.stop(opt.init(np.random.default_rng(0))) is None


def test_population_after_a_restart_is_the_evaluated_one():
    opt = CMAES(GenomeSpec.box(3, -5, 5), CMAESConfig(restarts="ipop"))
    rng = np.random.default_rng(4)
    s = opt.init(rng)
    while s.restarts == 0:
        x, s = opt.ask(s, rng)
        s = opt.tell(s, x, sphere(x), rng)
    pop, cost = opt.population(s)
    assert np.array_equal(pop, x) and np.allclose(cost, sphere(x))
    assert s.lam == 2 * opt.lam0
    x2, _ = opt.ask(s, rng)
    assert x2.shape[0] == s.lam


def test_bipop_uses_small_and_large_regimes():
    _, s = run(lambda x: 10 * x.shape[1] + np.sum(x**2 - 10 * np.cos(2 * np.pi * x), axis=1),
               3, CMAESConfig(restarts="bipop", max_restarts=6), max_evals=60000, target=-1)
    assert s.restarts == 6
    assert s.large_restarts >= 1 and s.evals_small > 0


def test_injected_candidates_are_clipped_in_mahalanobis_norm():
    opt = CMAES(GenomeSpec.box(6, -100, 100), CMAESConfig(restarts="none"))
    rng = np.random.default_rng(0)
    s = opt.init(rng)
    x, s = opt.ask(s, rng)
    far = x.copy()
    far[0] = 90.0  # a wild candidate the caller substituted; it is also the best
    cost = np.arange(len(x), dtype=float)
    s2 = opt.tell(s, far, cost, rng)
    step = (s2.mean - s.mean) / s.sigma
    n = 6
    c_y = np.sqrt(n) + 2 * n / (n + 2)
    # the mean moves at most by the sum of the positive weights times c_y (Mahalanobis, C = I)
    assert np.linalg.norm(step) <= c_y + 1e-9


def test_checkpoint_round_trip_and_determinism():
    cfg = CMAESConfig(chaos=True, levy=True, chaos_patience=2)
    opt = make_cmaes(GenomeSpec.box(5, -3, 3), cfg)
    rng = np.random.default_rng(7)
    s = opt.init(rng)
    for _ in range(15):
        x, s = opt.ask(s, rng)
        s = opt.tell(s, x, sphere(x) + 3 * np.sin(5 * x).sum(1), rng)
    arrays, meta = state_to_arrays(s)
    s_back = state_from_arrays(CMAESState, arrays, meta)
    bits = rng.bit_generator.state
    rng_b = np.random.default_rng()
    rng_b.bit_generator.state = bits
    xa, _ = opt.ask(s, rng)
    xb, _ = opt.ask(s_back, rng_b)
    assert np.array_equal(xa, xb)
    _, s1 = run(rosenbrock, 4, cfg, seed=11, max_evals=2000)
    _, s2 = run(rosenbrock, 4, cfg, seed=11, max_evals=2000)
    assert np.array_equal(s1.best_x, s2.best_x) and s1.chaos_jumps == s2.chaos_jumps
    assert s1.chaos_jumps > 0 and s1.levy_moves > 0


def test_invalid_config_rejected():
    for bad in (dict(sigma0=0), dict(restarts="lmm"), dict(chaos=True, chaos_mu=2.5),
                dict(levy=True, levy_beta=3.0), dict(pop_size=1)):
        with pytest.raises(ValueError):
            CMAESConfig(**bad).validate()


def test_initial_population_sets_the_mean_and_mutate_is_rejected():
    g = GenomeSpec.box(3, -5, 5)
    opt = CMAES(g, CMAESConfig())
    pop = np.array([[1.0, 2.0, -1.0], [3.0, 0.0, -3.0]])
    s = opt.init(np.random.default_rng(0), pop)
    assert np.allclose(opt.to_genome(s.mean), [2.0, 1.0, -2.0])
    # the same random stream as without a population
    r1, r2 = np.random.default_rng(5), np.random.default_rng(5)
    opt.init(r1, pop), opt.init(r2)
    assert r1.bit_generator.state == r2.bit_generator.state
    with pytest.raises(ValueError, match="mutate"):
        make_cmaes(g, CMAESConfig(), mutate=lambda x, rng, rate: x)


def test_generation_counts_every_generation_across_restarts():
    opt, s = run(sphere, 3, CMAESConfig(restarts="ipop", max_restarts=2, tolfun=1e-6),
                 max_evals=4000, target=-1)
    assert s.restarts >= 1
    assert s.generation > s.restart_generation
    assert s.evaluations >= s.generation * opt.lam0
