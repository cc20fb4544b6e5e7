"""One rule for every closed loop: the control period is a whole number of physics steps."""

from __future__ import annotations

import pytest

from evomotion.sim.control_period import whole_steps


@pytest.mark.parametrize("period, dt, most, steps", [
    (0.02, 0.004, None, 5), (0.004, 0.004, None, 1), (0.02, 0.002, None, 10),
    (0.021, 0.004, None, None), (0.0, 0.004, None, None), (1e-300, 0.004, None, None),
    (float("inf"), 0.004, None, None), (float("nan"), 0.004, None, None),
    (4.0, 0.004, 1000, 1000), (4.004, 0.004, 1000, None), (1e300, 0.004, 1000, None),
])
def test_whole_steps(period, dt, most, steps):
    assert whole_steps(period, dt, most) == steps
