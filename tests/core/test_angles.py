"""The shared angle wrap (it replaced five copies): the same values, bit for bit, as the
formulas it replaced, in range, one turn apart from the input."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from evomotion.core.angles import wrap_angle, wrap_angle_upper

ANGLES = st.floats(-1e6, 1e6, allow_nan=False)


@given(ANGLES)
def test_wrap_is_the_replaced_formula_and_in_range(a):
    w = wrap_angle(a)
    assert isinstance(w, float) and w == (a + math.pi) % (2 * math.pi) - math.pi
    assert -math.pi <= w < math.pi
    u = wrap_angle_upper(a)
    assert isinstance(u, float) and u == -((-a + np.pi) % (2 * np.pi) - np.pi)
    assert -math.pi < u <= math.pi
    assert abs(math.remainder(a - w, 2 * math.pi)) < 1e-6 * max(1.0, abs(a))


@given(st.lists(ANGLES, min_size=1, max_size=20))
def test_arrays_wrap_elementwise(values):
    a = np.array(values)
    assert np.array_equal(wrap_angle(a), [wrap_angle(v) for v in values])
    assert np.array_equal(wrap_angle_upper(a), [wrap_angle_upper(v) for v in values])


def test_the_ends_of_the_turn():
    assert wrap_angle(math.pi) == -math.pi and wrap_angle_upper(math.pi) == math.pi
    assert wrap_angle(-math.pi) == -math.pi and wrap_angle_upper(-math.pi) == math.pi
