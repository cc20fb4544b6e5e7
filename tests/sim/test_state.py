"""The recorded state's layout, read from the model, for any robot."""

from __future__ import annotations

import numpy as np

from evomotion.sim import state
from evomotion.sim.robots import load_robot, nao


def test_the_layout_is_read_from_the_model():
    for name in ("nao", "op3"):
        r = load_robot(name)
        m = r.model
        assert r.state0.size == state.state_size(m)
        assert state.qpos_address(m) == 0 and state.qvel_address(m) == 0  # the free joint
        states = np.stack([r.state0, r.state0])
        np.testing.assert_array_equal(state.state_qpos(m, states, n=3)[0], r.state0[1:4])
        assert state.state_qpos_all(m, states).shape == (2, m.nq)
        assert state.state_qvel(m, states, n=6).shape == (2, 6)
    m = nao.load_model()
    assert nao.state_qpos(m, np.arange(100.0), n=3).tolist() == [1.0, 2.0, 3.0]
    assert nao.STATE_SPEC == state.STATE_SPEC and nao.STATE_QPOS_OFFSET == state.QPOS_OFFSET
