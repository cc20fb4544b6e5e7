"""Scenes on the NAO MJCF and the named state accessors."""

import mujoco
import numpy as np

from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.scene import SOLE_SENSORS, scene_xml, sensor_slices
from evomotion.sim.rollout import BatchSimulator

BOX = '<body name="box" pos="1 0 0.05"><freejoint name="box"/><geom type="box" size=".05 .05 .05"/></body>\n'  # noqa: E501


def test_scene_adds_bodies_and_sensors_after_the_models_own():
    assert scene_xml() == nao.model_xml()
    model = mujoco.MjModel.from_xml_string(scene_xml(BOX, SOLE_SENSORS))
    sl = sensor_slices(model)
    assert list(sl) == ["l_sole", "r_sole", "l_contact", "r_contact", "l_xaxis", "r_xaxis"]
    assert sl["l_sole"] == slice(0, 3) and sl["l_contact"].stop - sl["l_contact"].start == 7
    assert nao.qpos_address(model) == 0 and nao.qpos_address(model, "box") == 7 + 22
    assert nao.qvel_address(model, "box") == 6 + 22
    assert model.nu == 22


def test_state_accessors_read_recorded_states():
    model = mujoco.MjModel.from_xml_string(scene_xml(BOX))
    data = nao.initial_data(model)
    data.joint("box").qvel[:] = [0.1, 0.2, 0, 0, 0, 0]
    state = nao.get_state(model, data)
    np.testing.assert_array_equal(nao.state_qpos(model, state, "box", 3), data.qpos[29:32])
    np.testing.assert_array_equal(nao.state_qvel(model, state, "box", 2), [0.1, 0.2])
    np.testing.assert_array_equal(nao.state_qpos(model, state, n=3), data.qpos[:3])
    np.testing.assert_array_equal(nao.state_qpos_all(model, state), data.qpos)
    with BatchSimulator(model, 1) as sim:
        states = sim.run(state, np.tile(nao.pose_vector(), (2, 5, 1)))
    assert nao.state_qpos(model, states, nao.ROOT_JOINT, 2).shape == (2, 5, 2)
    for name in nao.JOINTS:  # tree order of the MJCF, not the actuator order of JOINTS
        assert nao.qpos_address(model, name) == model.joint(name).qposadr[0]
        assert nao.qvel_address(model, name) == model.joint(name).dofadr[0]
