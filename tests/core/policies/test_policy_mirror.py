"""Mirror-symmetric structured policies (core/policies/mirror.py): every parameter vector the
basis makes acts as its own mirror image, exactly, for random mirrors, harmonics, commands and
gains; the normaliser fed with mirrored moments is exactly symmetric; bad mirrors are refused."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.core.policies import StructuredSpec
from evomotion.core.policies.mirror import (
    MirrorBasis,
    SignedPermutation,
    structured_mirror,
    with_mirror_image,
)
from evomotion.core.policies.normalizer import init, mean_std, merge


def _random_mirror(rng: np.random.Generator, n: int, fixed: tuple[int, ...] = ()
                   ) -> SignedPermutation:
    """Pairs swapped with a sign, the rest on themselves with a random sign (``fixed``: +1)."""
    free = [i for i in range(n) if i not in fixed]
    rng.shuffle(free)
    perm, sign = np.arange(n), np.ones(n)
    k = int(rng.integers(0, len(free) // 2 + 1))
    for i, j in zip(free[:k], free[k:2 * k], strict=True):
        perm[i], perm[j] = j, i
        sign[i] = sign[j] = rng.choice([-1.0, 1.0])
    for i in free[2 * k:]:
        sign[i] = rng.choice([-1.0, 1.0])
    return SignedPermutation(perm, sign)


@settings(max_examples=40, deadline=None, derandomize=True, database=None)
@given(seed=st.integers(0, 2**31), a=st.integers(1, 6), extra=st.integers(0, 6),
       H=st.integers(0, 3), m=st.integers(1, 3), feedback=st.booleans())
def test_every_basis_policy_acts_as_its_own_mirror_image(seed, a, extra, H, m, feedback):
    rng = np.random.default_rng(seed)
    o = 2 + m + extra  # phase (0, 1), command (2..), other inputs
    cmd = tuple(range(2, 2 + m))
    spec = StructuredSpec(o, a, phase_columns=(0, 1), harmonics=H, command_columns=cmd,
                          command_feedback=feedback, clip_obs=np.inf)
    act = _random_mirror(rng, a)
    obs_m = _random_mirror(rng, o, fixed=(0, 1, *cmd))
    sign = obs_m.sign.copy()
    sign[list(cmd)] = rng.choice([-1.0, 1.0], size=m)  # a command's own signs
    obs_m = SignedPermutation(obs_m.perm, sign)
    basis = MirrorBasis.of(structured_mirror(spec, act, obs_m))
    assert 0 <= basis.dim <= spec.n_params
    params = np.tile(basis.expand(rng.normal(size=basis.dim)), (8, 1))
    # a symmetric normaliser, as with_mirror_image makes it
    count, mean, m2 = with_mirror_image(np.array([5.0]), rng.normal(size=(1, o)),
                                        rng.uniform(1, 2, size=(1, o)), obs_m)
    std = np.sqrt(m2[0] / count[0])
    phi = rng.uniform(0, 2 * np.pi, size=8)
    obs = rng.normal(size=(8, o))
    obs[:, 0], obs[:, 1] = np.sin(phi), np.cos(phi)
    mirrored = obs_m.apply(obs)
    mirrored[:, 0], mirrored[:, 1] = np.sin(phi + np.pi), np.cos(phi + np.pi)
    y = spec.act(params, obs, mean[0], std)
    np.testing.assert_allclose(spec.act(params, mirrored, mean[0], std), act.apply(y),
                               atol=1e-12)
    if basis.dim < spec.n_params:  # a generic vector is not symmetric (the test can fail)
        other = np.tile(rng.normal(size=spec.n_params), (8, 1))
        y = spec.act(other, obs, mean[0], std)
        assert not np.allclose(spec.act(other, mirrored, mean[0], std), act.apply(y))
    # reduce(expand(z)) = z
    z = rng.normal(size=basis.dim)
    np.testing.assert_allclose(basis.reduce(basis.expand(z)), z, atol=1e-15)


def test_mirrored_moments_keep_the_running_normaliser_exactly_symmetric():
    rng = np.random.default_rng(3)
    o = 7
    mirror = _random_mirror(rng, o)
    stats = init(o)
    for _ in range(5):
        count, mean, m2 = with_mirror_image(rng.integers(1, 50, 4).astype(float),
                                            rng.normal(size=(4, o)),
                                            rng.uniform(0, 3, (4, o)), mirror)
        for c, mu, s in zip(count, mean, m2, strict=True):
            stats = merge(stats, (np.array(int(c)), mu, s))
    mu, sd = mean_std(stats)
    assert np.array_equal(mirror.apply(mu), mu) and np.array_equal(sd[mirror.perm], sd)


def test_bad_mirrors_are_refused():
    with pytest.raises(ValueError, match="undo itself"):
        SignedPermutation([1, 2, 0], [1, 1, 1])
    with pytest.raises(ValueError, match="undo itself"):
        SignedPermutation([1, 0], [1, -1])
    with pytest.raises(ValueError, match="signs"):
        SignedPermutation([0], [0.5])
    spec = StructuredSpec(4, 1, phase_columns=(0, 1), harmonics=1, command_columns=(2,))
    swap_phase = SignedPermutation([1, 0, 2, 3], [1, 1, 1, 1])
    with pytest.raises(ValueError, match="phase and command"):
        structured_mirror(spec, SignedPermutation([0], [1]), swap_phase)
