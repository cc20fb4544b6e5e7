import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.sim.robots import nao
from evomotion.studies.humanoid_step.encoding import ServoEncoding
from evomotion.studies.humanoid_step.problem import (
    PAPER_TABLE1,
    leg_initial_pose,
    servo_bounds,
)

Q0 = leg_initial_pose()
LO, HI = servo_bounds(nao.load_model())


def _enc(kind, K=6, T=1.2):
    return ServoEncoding(kind, Q0, LO, HI, K, T)


@settings(max_examples=25, deadline=None)
@given(st.sampled_from(["linear", "spline"]), st.integers(2, 12), st.integers(0, 10_000))
def test_knot_encodings_pass_exactly_through_knots(kind, K, seed):
    enc = _enc(kind, K)
    g = enc.genome(nao.LEG_SERVOS).sample(np.random.default_rng(seed), 4)
    knots = enc.knots(g)
    assert knots.shape == (4, K + 1, 10)
    np.testing.assert_array_equal(knots[:, 0], np.broadcast_to(Q0, (4, 10)))
    np.testing.assert_array_equal(knots[:, -1], np.broadcast_to(Q0, (4, 10)))
    out = enc.targets(g, enc.knot_times)
    np.testing.assert_allclose(out, knots, atol=1e-12)


def test_linear_is_linear_between_knots():
    enc = _enc("linear", 4, 2.0)
    g = enc.genome(nao.LEG_SERVOS).sample(np.random.default_rng(1), 3)
    k = enc.knots(g)
    mid = enc.targets(g, np.array([0.25, 0.6]))  # knots every 0.5 s
    np.testing.assert_allclose(mid[:, 0], 0.5 * (k[:, 0] + k[:, 1]), atol=1e-12)
    np.testing.assert_allclose(mid[:, 1], 0.8 * k[:, 1] + 0.2 * k[:, 2], atol=1e-12)


def test_spline_starts_and_ends_at_rest():
    enc = _enc("spline", 5, 1.0)
    g = enc.genome(nao.LEG_SERVOS).sample(np.random.default_rng(2), 2)
    eps = 1e-6
    unclipped = ServoEncoding("spline", Q0, LO - 10, HI + 10, 5, 1.0)
    y = unclipped.targets(g, np.array([0.0, eps, 1.0 - eps, 1.0]))
    assert np.max(np.abs(y[:, 1] - y[:, 0])) / eps < 1e-3
    assert np.max(np.abs(y[:, 3] - y[:, 2])) / eps < 1e-3


def test_harmonic_formula_and_pinned_ends():
    enc = _enc("harmonic", 4, 2.0)
    spec = enc.genome(nao.LEG_SERVOS)
    assert spec.dim == 31
    g = np.zeros((1, 31))
    g[0, 0:3] = [0.05, -0.02, 0.03]  # RHipPitch a, b, c
    g[0, 30] = 3.0  # omega rad/s
    y = enc.targets(g, np.array([0.0, 1.0, 2.0]))
    np.testing.assert_allclose(y[0, 0], Q0, atol=1e-12)
    np.testing.assert_allclose(y[0, 2], Q0, atol=1e-12)
    expect = Q0[0] + 0.05 * np.sin(3.0) - 0.02 * np.cos(3.0) + 0.03  # window = 1 at T/2
    assert y[0, 1, 0] == pytest.approx(expect, abs=1e-12)
    np.testing.assert_allclose(y[0, 1, 1:], Q0[1:], atol=1e-12)


def test_bounds_are_paper_table1_within_model_ranges():
    model = nao.load_model()
    rng = nao.joint_ranges(model, nao.LEG_SERVOS)
    for i, name in enumerate(nao.LEG_SERVOS):
        t_lo, t_hi = PAPER_TABLE1[name]
        assert LO[i] == pytest.approx(max(t_lo, rng[i, 0]))
        assert HI[i] == pytest.approx(min(t_hi, rng[i, 1]))
        assert LO[i] <= Q0[i] <= HI[i]
    lo4, hi4 = servo_bounds(model, 0.25)
    np.testing.assert_allclose(hi4 - lo4, 0.25 * (HI - LO))


def test_genome_layout_servo_major():
    enc = _enc("linear", 20, 2.0)
    spec = enc.genome(nao.LEG_SERVOS)
    assert spec.dim == 10 * 19
    assert spec.slices["RHipPitch"] == slice(0, 19)
    assert spec.slices["LAnkleRoll"] == slice(171, 190)
