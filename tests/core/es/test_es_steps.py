"""The optimizer steps: Adam (Kingma & Ba 2015, Alg. 1) and ClipUp (Toklu et al. 2020)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from evomotion.core.es.adam import adam_step
from evomotion.core.es.clipup import clipup_step


def test_adam_two_steps_by_hand():
    theta, m, v = np.array([1.0]), np.zeros(1), np.zeros(1)
    kw = dict(learning_rate=0.1, beta1=0.9, beta2=0.999, eps=0.0)
    theta, m, v = adam_step(theta, np.array([2.0]), m, v, 1, **kw)
    # m1 = 0.1 * 2 = 0.2, v1 = 0.001 * 4 = 0.004, m^ = 2, v^ = 4: theta1 = 1 - 0.1 * 2 / 2
    np.testing.assert_allclose([theta[0], m[0], v[0]], [0.9, 0.2, 0.004])
    theta, m, v = adam_step(theta, np.array([-1.0]), m, v, 2, **kw)
    # m2 = 0.18 - 0.1 = 0.08, v2 = 0.003996 + 0.001 = 0.004996
    # m^ = 0.08 / 0.19, v^ = 0.004996 / 0.001999
    np.testing.assert_allclose([m[0], v[0]], [0.08, 0.004996])
    np.testing.assert_allclose(theta[0], 0.9 - 0.1 * (0.08 / 0.19) / math.sqrt(0.004996 / 0.001999))
    assert theta[0] == pytest.approx(0.873366, abs=1e-6)


def test_adam_returns_new_arrays_and_checks_t():
    theta, m, v = np.ones(3), np.zeros(3), np.zeros(3)
    out = adam_step(theta, np.ones(3), m, v, 1, learning_rate=0.1)
    assert all(a is not b for a, b in zip(out, (theta, m, v), strict=True))
    assert theta.tolist() == [1.0] * 3 and m.tolist() == [0.0] * 3
    with pytest.raises(ValueError):
        adam_step(theta, np.ones(3), m, v, 0, learning_rate=0.1)


vec = arrays(float, 5, elements=st.floats(-1e3, 1e3))


@given(vec, vec, st.floats(1e-4, 10), st.floats(1e-4, 10), st.floats(0, 0.999))
def test_clipup_never_exceeds_max_speed(grad, velocity, step, max_speed, momentum):
    x0 = np.zeros(5)
    x1, v1 = clipup_step(x0, grad, velocity, step_size=step, max_speed=max_speed,
                         momentum=momentum)
    assert np.linalg.norm(v1) <= max_speed * (1 + 1e-12)
    np.testing.assert_array_equal(x1, x0 + v1)


def test_clipup_normalises_the_gradient_and_clips():
    x, v = clipup_step(np.zeros(2), np.array([300.0, 400.0]), np.zeros(2), step_size=0.5,
                       max_speed=1.0, momentum=0.9)
    np.testing.assert_allclose(v, [0.3, 0.4])  # the gradient's scale does not matter
    x, v = clipup_step(x, np.array([3.0, 4.0]), v, step_size=0.5, max_speed=0.6, momentum=0.9)
    np.testing.assert_allclose(v, [0.36, 0.48])  # 0.9 v + 0.5 u = (0.57, 0.76) -> norm 0.6
    _, v0 = clipup_step(x, np.zeros(2), v, step_size=0.5, max_speed=0.6, momentum=0.5)
    np.testing.assert_allclose(v0, 0.5 * v)
