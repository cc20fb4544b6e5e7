"""Observation specs and their vectorised builder (sim/observations.py)."""

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.errors import InputError
from evomotion.sim.observations import (
    CHANNELS,
    ObservationBuilder,
    ObservationSpec,
    columns_of,
    observation_names,
    observation_size,
)
from evomotion.sim.robots import load_robot

ALL = ObservationSpec(tuple(CHANNELS), phase_period_s=0.8, command_size=3)


@pytest.fixture(scope="module")
def robot():
    return load_robot("nao")


def test_layout_matches_the_spec(robot):
    names = observation_names(ALL, robot)
    sizes = {"joint_pos": 10, "joint_vel": 10, "gravity": 3, "roll_pitch": 2, "gyro": 3,
             "torso_velocity": 3, "torso_height": 1, "foot_contact": 2, "phase": 2, "command": 3}
    assert observation_size(ALL, robot) == len(names) == sum(sizes.values())
    build = ObservationBuilder(ALL, robot)
    start = 0
    for channel in ALL.channels:  # in the spec's order, contiguous
        assert columns_of(names, channel) == list(range(start, start + sizes[channel]))
        assert build.slices[channel] == slice(start, start + sizes[channel])
        start += sizes[channel]
    evolved = [n.split(":")[1] for n in names if n.startswith("joint_pos:")]
    assert evolved == list(robot.evolved)  # the default action order
    assert names[columns_of(names, "foot_contact")[0]] == "foot_contact:left"
    every = ObservationSpec(("joint_pos",), joints="all")
    assert observation_size(every, robot) == robot.model.nu == 22


@pytest.mark.parametrize("spec", [ObservationSpec(()),
                                  ObservationSpec(("nose",)),
                                  ObservationSpec(("gyro", "gyro")),
                                  ObservationSpec(("phase",)),
                                  ObservationSpec(("command",)),
                                  ObservationSpec(joints="arms")])
def test_bad_specs_are_one_line_errors(robot, spec):
    with pytest.raises(InputError):
        observation_size(spec, robot)


def _forward(robot, qpos, qvel, time):
    m = robot.model
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:], d.time = qpos, qvel, time
    mujoco.mj_forward(m, d)
    state = np.empty(mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(m, d, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    return d, state


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(
    lambda q: np.linalg.norm(q) > 0.1), st.lists(st.floats(-2, 2), min_size=6, max_size=6),
    st.floats(0, 10))
def test_imu_channels_match_mujoco_frames(quat, vel, time):
    robot = load_robot("nao")
    m = robot.model
    qpos = robot.state0[1:1 + m.nq].copy()
    qpos[3:7] = np.asarray(quat) / np.linalg.norm(quat)
    qvel = np.zeros(m.nv)
    qvel[:6] = vel
    d, state = _forward(robot, qpos, qvel, time)
    build = ObservationBuilder(ALL, robot)
    obs = build(state[None], d.sensordata[None].copy(), np.array([[1.0, 2.0, 3.0]]))[0]
    rot = d.xmat[1].reshape(3, 3)  # the torso's world rotation
    get = {c: obs[s] for c, s in build.slices.items()}
    np.testing.assert_allclose(get["gravity"], rot.T @ [0, 0, -1], atol=1e-12)
    np.testing.assert_allclose(get["torso_velocity"], rot.T @ np.asarray(vel[:3]), atol=1e-12)
    np.testing.assert_allclose(get["gyro"], vel[3:], atol=0)
    roll, pitch = get["roll_pitch"]  # ZYX Euler: R = Rz(yaw) Ry(pitch) Rx(roll)
    np.testing.assert_allclose([np.sin(pitch), np.cos(pitch) * np.sin(roll)],
                               [-rot[2, 0], rot[2, 1]], atol=1e-9)
    phase = 2 * np.pi * time / 0.8
    np.testing.assert_allclose(get["phase"], [np.sin(phase), np.cos(phase)], atol=1e-12)
    np.testing.assert_array_equal(get["command"], [1.0, 2.0, 3.0])
    assert get["torso_height"][0] == qpos[2]


def test_joints_and_contacts(robot):
    m = robot.model
    qpos = robot.state0[1:1 + m.nq].copy()
    qvel = np.arange(m.nv) * 0.01
    d, state = _forward(robot, qpos, qvel, 0.0)
    build = ObservationBuilder(ALL, robot)
    cols = m.actuator_trnid[robot.columns, 0]
    states = np.stack([state, state])
    lifted = states.copy()
    lifted[1, 3] += 0.2  # the torso 20 cm higher: no foot touches
    sens = np.stack([d.sensordata, np.zeros(m.nsensordata)])
    obs = build(lifted, sens, np.zeros((2, 3)))
    np.testing.assert_array_equal(obs[:, build.slices["joint_pos"]],
                                  lifted[:, 1 + m.jnt_qposadr[cols]])
    np.testing.assert_array_equal(obs[:, build.slices["joint_vel"]],
                                  lifted[:, 1 + m.nq + m.jnt_dofadr[cols]])
    contacts = obs[:, build.slices["foot_contact"]]
    np.testing.assert_array_equal(contacts[1], [0.0, 0.0])
    assert set(contacts[0].tolist()) <= {0.0, 1.0}
    with pytest.raises(ValueError):
        build(states)  # foot contacts need the sensors
