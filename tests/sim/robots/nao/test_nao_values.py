"""The NAO's own initial states refuse absurd clearances (issue 31: ``clearance_m = 1e300``
ran with MuJoCo's instability warnings instead of being one error line)."""

from __future__ import annotations

import pytest

from evomotion.errors import InputError
from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.replay import start_state


@pytest.mark.parametrize("value,fragment", [
    (1e300, "expected a value in [0.0, 0.1]"), (float("nan"), "finite"),
    (float("inf"), "finite"), (-0.01, "[0.0, 0.1]"),
])
def test_clearance_is_finite_and_physical(value, fragment):
    model = nao.load_model()
    with pytest.raises(InputError, match="clearance_m") as e:
        nao.initial_data(model, clearance_m=value)
    assert fragment in str(e.value)
    for start in ("standing", "face-down"):
        with pytest.raises(InputError, match="clearance_m"):
            start_state(model, nao.pose_vector(), start, clearance_m=value)


def test_the_default_clearance_still_stands():
    model = nao.load_model()
    data = nao.initial_data(model)
    assert abs(min(data.site("l_sole_site").xpos[2], data.site("r_sole_site").xpos[2])
               - 0.0005) < 1e-12
