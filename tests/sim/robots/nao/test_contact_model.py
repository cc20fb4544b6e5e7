"""The sole/floor contact keeps Webots' own motions on their intended turn or straight line."""

from __future__ import annotations

import math

import pytest

from evomotion.sim.robots.nao.replay import replay
from fixture_files import WEBOTS_MOTIONS

FIXTURES = WEBOTS_MOTIONS
#: name -> (intended heading change in degrees, intended lateral direction or 0)
INTENT = {"TurnLeft40": (40.0, 0), "TurnLeft60": (60.0, 0), "TurnRight40": (-40.0, 0),
          "SideStepLeft": (0.0, 1), "SideStepRight": (0.0, -1), "HandWave": (0.0, 0),
          "Shoot": (0.0, 0)}


@pytest.mark.parametrize("name", sorted(INTENT))
def test_fixture_keeps_its_turn_or_line(name):
    want_deg, side = INTENT[name]
    out = replay(FIXTURES / f"{name}.motion")
    assert not out["fell"]
    assert abs(math.degrees(out["heading_change_rad"]) - want_deg) <= 2.0
    dx, dy = out["displacement_m"]
    if side:
        assert side * dy >= 0.05 and abs(dx) <= 0.015  # a side step, not a drift forward
    elif want_deg == 0.0:
        assert math.hypot(dx, dy) <= 0.01  # standing motions stay where they are


def test_sole_contact_has_torsional_friction():
    from evomotion.sim.robots import nao

    model = nao.load_model()
    for name in ("l_sole", "r_sole"):
        g = model.geom(name)
        assert int(g.condim[0]) == 4 and g.friction[1] >= 0.01
