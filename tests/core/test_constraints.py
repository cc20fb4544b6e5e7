"""Feasibility-first ranking (Deb 2000) as a scalar fitness."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.core.constraints import feasibility_first, is_feasible

objs = st.floats(-50, 50, allow_nan=False)
# violations apart by less than the float spacing at |floor| + 1 (~4e-15) tie (documented)
viol = st.one_of(st.just(0.0), st.floats(1e-9, 1e6, allow_nan=False))


@settings(max_examples=200, deadline=None)
@given(a=objs, va=viol, b=objs, vb=viol, sense=st.sampled_from(["max", "min"]))
def test_debs_three_rules(a, va, b, vb, sense):
    floor = -20.0 if sense == "max" else 20.0
    fa, fb = feasibility_first(np.array([a, b]), np.array([va, vb]), sense, floor)
    better = (lambda x, y: x > y) if sense == "max" else (lambda x, y: x < y)
    clip = (lambda x: max(x, floor)) if sense == "max" else (lambda x: min(x, floor))
    if va == 0 and vb > 0:
        assert better(fa, fb)  # feasible beats infeasible, whatever the objectives
    elif va == 0 and vb == 0:
        assert (fa, fb) == (clip(a), clip(b))  # both feasible: the objective decides
    elif va > 0 and vb > 0 and vb - va > 1e-12 * max(1.0, vb):
        assert better(fa, fb)  # both infeasible: the smaller violation wins
    assert bool(is_feasible(np.array([fa]), sense, floor)[0]) == (va == 0)


def test_nan_violation_is_the_worst():
    f = feasibility_first(np.array([1.0, 1.0]), np.array([np.nan, 1e9]), "max", -20.0)
    assert f[0] < f[1] and f[0] == -np.inf
