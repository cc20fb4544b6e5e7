"""The shared noise table (``algorithm.noise_table``) of the strategies (the mirrored ones and
SNES): windows of one fixed table, offsets from the passed generator; the clipping skip changes
nothing."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.core.algorithms import make_optimizer
from evomotion.core.es.common import NOISE_TABLE_SEED, noise_table
from evomotion.core.problem import GenomeSpec

MIRRORED = ("ars", "openai_es", "pgpe")
SCALE = {"ars": "noise_std", "openai_es": "sigma", "pgpe": "stdev_init"}
ALL = (*MIRRORED, "snes")


@pytest.mark.parametrize("name", MIRRORED)
def test_perturbations_are_windows_of_the_table(name):
    d, size = 7, 1000
    opt = make_optimizer(name, GenomeSpec.box(d, -1e3, 1e3), pop_size=8, noise_table=size)
    state = opt.init(np.random.default_rng(0))
    x, _ = opt.ask(state, np.random.default_rng(3))
    scale = getattr(opt.cfg, SCALE[name])
    eps = (x[:4] - opt.center(state)) / scale
    offsets = np.random.default_rng(3).integers(0, size - d + 1, size=4)
    table = np.random.default_rng(NOISE_TABLE_SEED).standard_normal(size)
    np.testing.assert_allclose(eps, table[offsets[:, None] + np.arange(d)], atol=1e-9)
    np.testing.assert_array_equal(x[:4] + x[4:], 2 * opt.center(state)[None].repeat(4, 0))


def test_snes_samples_are_windows_of_the_table_and_fresh_noise_is_unchanged():
    d, size, lam = 7, 1000, 5
    genome = GenomeSpec.box(d, -1e3, 1e3)
    opt = make_optimizer("snes", genome, pop_size=lam, sigma_init=0.3, noise_table=size)
    state = opt.init(np.random.default_rng(0))
    x, _ = opt.ask(state, np.random.default_rng(3))
    offsets = np.random.default_rng(3).integers(0, size - d + 1, size=lam)
    table = np.random.default_rng(NOISE_TABLE_SEED).standard_normal(size)
    np.testing.assert_allclose((x - opt.center(state)) / 0.3,
                               table[offsets[:, None] + np.arange(d)], atol=1e-9)
    fresh = make_optimizer("snes", genome, pop_size=lam, sigma_init=0.3)
    y, _ = fresh.ask(fresh.init(np.random.default_rng(0)), np.random.default_rng(3))
    z = np.random.default_rng(3).standard_normal((lam, d)) * 0.3 + fresh.center(state)
    np.testing.assert_array_equal(y, z)  # what SNES drew before the table existed


def test_the_table_is_a_function_of_its_size_and_read_only():
    a = noise_table(500)
    assert a is noise_table(500) and not a.flags.writeable
    np.testing.assert_array_equal(a, np.random.default_rng(NOISE_TABLE_SEED).standard_normal(500))


@pytest.mark.parametrize("name", ALL)
def test_same_generator_same_population_and_runs_repeat(name):
    genome = GenomeSpec.box(12, -2.0, 2.0)

    def run() -> np.ndarray:
        opt = make_optimizer(name, genome, pop_size=10, noise_table=4096)
        rng = np.random.default_rng(11)
        state = opt.init(rng)
        for _ in range(5):
            x, state = opt.ask(state, rng)
            state = opt.tell(state, x, (x**2).sum(axis=1), rng)
        return opt.center(state)

    np.testing.assert_array_equal(run(), run())


@settings(max_examples=30, deadline=None)
@given(bound=st.floats(0.01, 5.0), scale=st.floats(1e-3, 2.0), seed=st.integers(0, 2**16),
       table=st.sampled_from([0, 64, 4096]), name=st.sampled_from(["openai_es", "snes"]))
def test_asked_genomes_are_inside_the_bounds_and_equal_to_clipping(bound, scale, seed, table,
                                                                   name):
    """The clip is skipped only where it would change nothing."""
    genome = GenomeSpec.box(6, -bound, bound)
    key = "sigma" if name == "openai_es" else "sigma_init"
    opt = make_optimizer(name, genome, pop_size=8, noise_table=table, **{key: scale})
    state = opt.init(np.random.default_rng(seed))
    x, _ = opt.ask(state, np.random.default_rng(seed))
    assert (x >= -bound).all() and (x <= bound).all()
    np.testing.assert_array_equal(x, np.clip(x, -bound, bound))


@pytest.mark.parametrize("value, match", [(-1, "noise_table"), (3, "at least the genome's 5"),
                                          (2.5, "noise_table"), (2**40, "noise_table")])
@pytest.mark.parametrize("name", ALL)
def test_bad_table_sizes_are_one_line_errors(name, value, match):
    with pytest.raises(ValueError, match=match) as e:
        make_optimizer(name, GenomeSpec.box(5, -1.0, 1.0), pop_size=4, noise_table=value)
    assert "\n" not in str(e.value)
