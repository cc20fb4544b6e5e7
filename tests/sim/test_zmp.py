"""ZMP / CoP from MuJoCo contacts on hand-built static cases, and the polygon helpers."""

from __future__ import annotations

import mujoco
import numpy as np

from evomotion.sim.zmp import (
    centre_of_pressure,
    convex_hull,
    floor_contacts,
    support_margin,
    zmp_margin,
)

BOX_XML = """
<mujoco>
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="box" pos="0.3 -0.2 0.051">
      <freejoint/>
      <geom type="box" size="0.10 0.05 0.05" mass="2.0"/>
      {extra}
    </body>
  </worldbody>
</mujoco>
"""


def settle(extra: str = "") -> tuple[mujoco.MjModel, mujoco.MjData]:
    model = mujoco.MjModel.from_xml_string(BOX_XML.format(extra=extra))
    data = mujoco.MjData(model)
    for _ in range(500):  # 1 s
        mujoco.mj_step(model, data)
    return model, data


def test_box_at_rest_cop_is_under_the_centre_and_carries_the_weight():
    model, data = settle()
    floor = model.geom("floor").id
    pos, force = floor_contacts(model, data, floor)
    cop, total = centre_of_pressure(pos, force)
    assert abs(total - 2.0 * 9.81) < 0.05 * 2.0 * 9.81
    assert np.allclose(cop, [0.3, -0.2], atol=2e-3)
    hull = convex_hull(pos[:, :2])
    assert np.allclose(np.sort(hull[:, 0]), [0.2, 0.2, 0.4, 0.4], atol=2e-3)
    assert abs(zmp_margin(model, data, floor) - 0.05) < 3e-3  # 5 cm to the long edges


def test_offset_mass_moves_the_cop_to_the_combined_com():
    # a 2 kg lump 8 cm along +x on top of the 2 kg box: combined CoM x = 0.3 + 0.04
    model, data = settle('<geom type="sphere" size="0.02" pos="0.08 0 0.07" mass="2.0"/>')
    cop, total = centre_of_pressure(*floor_contacts(model, data, model.geom("floor").id))
    assert abs(total - 4.0 * 9.81) < 0.05 * 4.0 * 9.81
    assert np.allclose(cop, [0.34, -0.2], atol=3e-3)
    assert abs(zmp_margin(model, data, model.geom("floor").id) - 0.05) < 3e-3


def test_margin_sign_and_value_on_a_square():
    sq = convex_hull(np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]]))
    assert len(sq) == 4
    assert support_margin(np.array([0.5, 0.5]), sq) == 0.5
    assert np.isclose(support_margin(np.array([0.9, 0.5]), sq), 0.1)
    assert np.isclose(support_margin(np.array([1.5, 0.5]), sq), -0.5)
    assert np.isclose(support_margin(np.array([2.0, 2.0]), sq), -np.sqrt(2))
    assert support_margin(np.array([0.5, 0.5]), sq[:2]) == -np.inf


def test_no_contact_gives_no_support():
    model = mujoco.MjModel.from_xml_string(BOX_XML.format(extra="").replace("0.051", "1.0"))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    assert zmp_margin(model, data, model.geom("floor").id) == -np.inf
