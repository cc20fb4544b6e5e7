"""MuJoCo Warp backend (``problem.backend = "warp"``) against ``mujoco.rollout``, on Warp's CPU
device (the same code runs on a CUDA GPU; ``benchmarks/bench_gpu.py`` measures it there).

Tolerances (measured on the standing NAO and the 7 Webots fixture motions: joints <= 3e-6 rad
and torso <= 3e-7 m over 0.5 s; displacement <= 2.3 mm and heading <= 0.019 rad after 3 s;
float32 against float64):
joint angles and torso pose agree within 1e-4 over the first 0.5 s; over 3 s, fall / no fall
is the same and the displacement agrees within 1 cm and the heading within 0.05 rad.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco_warp")

from evomotion.errors import InputError  # noqa: E402
from evomotion.sim.motion import read_motion  # noqa: E402
from evomotion.sim.robots import nao  # noqa: E402
from evomotion.sim.robots.nao.replay import motion_targets  # noqa: E402
from evomotion.sim.rollout import (  # noqa: E402
    BatchSimulator,
    fall_step,
    fell,
    rollout_segments,
    torso_track,
)
from evomotion.sim.warp_memory import bucket_size  # noqa: E402
from evomotion.sim.warp_rollout import WarpSimulator  # noqa: E402
from evomotion.sim.worlds import World, make_world, simulate_worlds  # noqa: E402
from fixture_files import WEBOTS_MOTIONS

FIXTURES = WEBOTS_MOTIONS
MOTIONS = ("SideStepLeft.motion", "TurnRight40.motion", "Shoot.motion")
NSTEP = 750  # 3 s
EARLY = 125  # 0.5 s
JOINT_TOL, TORSO_TOL = 1e-4, 1e-4
DISP_TOL_M, YAW_TOL_RAD = 0.01, 0.05


@pytest.fixture(scope="module")
def model():
    return nao.load_model()


@pytest.fixture(scope="module")
def warp_sim(model):
    return WarpSimulator(model, "cpu")


@pytest.fixture(scope="module")
def batch(model):
    """Initial states and controls: the standing NAO and three Webots motions, 3 s each."""
    dt = float(model.opt.timestep)
    inits, ctrls = [nao.initial_state(model)], [np.tile(nao.pose_vector(), (NSTEP, 1))]
    for name in MOTIONS:
        first, c = motion_targets(read_motion(FIXTURES / name), dt, NSTEP)
        inits.append(nao.initial_state(model, first))
        ctrls.append(c)
    return np.array(inits), np.array(ctrls)


def _cpu(model, inits, ctrl):
    with BatchSimulator(model, 1) as sim:
        return rollout_segments(lambda r, a, b, i: sim.run_with_sensors(i, ctrl[r, a:b]),
                                inits, ctrl.shape[1], model.nsensordata, None, 0)


@pytest.fixture(scope="module")
def both(model, warp_sim, batch):
    inits, ctrl = batch
    return _cpu(model, inits, ctrl), warp_sim.segment(inits, ctrl)


def test_first_half_second_agrees_with_mujoco_rollout(model, both):
    (sc, dc), (sw, dw) = both
    assert sw.shape == sc.shape and dw.shape == dc.shape
    cols = 1 + np.array([nao.qpos_address(model, j) for j in nao.JOINTS])
    joints = np.abs(sc[:, :EARLY, cols] - sw[:, :EARLY, cols]).max()
    torso = np.abs(sc[:, :EARLY, 1:8] - sw[:, :EARLY, 1:8]).max()
    assert joints < JOINT_TOL, joints
    assert torso < TORSO_TOL, torso
    assert np.allclose(sc[:, :, 0], sw[:, :, 0], atol=1e-5)  # time column


def test_three_seconds_agree_on_falls_displacement_and_heading(both):
    (sc, _), (sw, _) = both
    tc, tw = torso_track(sc), torso_track(sw)
    fall_c = fall_step(tc, nao.FALL_HEIGHT_M, nao.FALL_TILT_RAD) < NSTEP
    fall_w = fall_step(tw, nao.FALL_HEIGHT_M, nao.FALL_TILT_RAD) < NSTEP
    assert (fall_c == fall_w).all()
    disp_c = tc.xyz[:, -1, :2] - tc.xyz[:, 0, :2]
    disp_w = tw.xyz[:, -1, :2] - tw.xyz[:, 0, :2]
    assert np.linalg.norm(disp_c - disp_w, axis=1).max() < DISP_TOL_M
    assert np.abs(tc.yaw_rad[:, -1] - tw.yaw_rad[:, -1]).max() < YAW_TOL_RAD
    assert np.linalg.norm(disp_c, axis=1).max() > 0.05  # the motions do move the robot


def test_a_trajectory_does_not_depend_on_its_batch(warp_sim, batch):
    """Alone, padded into a batch of 4, or among others: the same states, bit for bit
    (the evaluators split populations in any way)."""
    inits, ctrl = batch
    short = ctrl[:, :60]
    together, _ = warp_sim.segment(inits, short)
    alone, _ = warp_sim.segment(inits[2:3], short[2:3])
    three, _ = warp_sim.segment(inits[1:4], short[1:4])
    np.testing.assert_array_equal(alone[0], together[2])
    np.testing.assert_array_equal(three[1], together[2])


def test_early_stop_packs_active_robots_and_keeps_their_states(model, warp_sim, batch):
    """Robots that fall stop being simulated; the rest are packed into a smaller batch and
    their states stay exactly those of the unsegmented rollout (warm start aside, within
    float32 noise)."""
    inits, ctrl = batch
    # make two robots fall: throw the arms and legs to their limits at once
    ctrl = ctrl[:, :250].copy()
    hi = nao.joint_ranges(model, nao.JOINTS)[:, 1]
    ctrl[2:4, :] = hi
    full, _ = warp_sim.segment(inits, ctrl)
    before = warp_sim.steps_simulated

    def fallen(s):
        return fell(s, 0.25, 0.5)

    seg, _ = rollout_segments(lambda r, a, b, i: warp_sim.segment(i, ctrl[r, a:b]), inits,
                              250, model.nsensordata, fallen, 25)
    stepped = warp_sim.steps_simulated - before
    down = fallen(full)
    assert down[2:4].all() and not down[[0, 1]].any()
    assert stepped < 4 * 250  # the fallen ones were not stepped to the end
    keep = ~down
    assert np.abs(seg[keep] - full[keep]).max() < 1e-3
    assert bucket_size(3) == 4 and bucket_size(4) == 4 and bucket_size(5) == 8
    assert bucket_size(1) == 1


def test_buffers_grow_when_contacts_overflow(model, batch):
    inits, ctrl = batch
    small = WarpSimulator(model, "cpu", nconmax=1, njmax=4)
    s_small, _ = small.segment(inits[:2], ctrl[:2, :50])
    s_ref, _ = WarpSimulator(model, "cpu").segment(inits[:2], ctrl[:2, :50])
    assert small.regrown >= 1 and small.nconmax > 1
    np.testing.assert_array_equal(s_small, s_ref)  # buffer sizes do not change results


def test_perturbed_worlds_agree_with_the_cpu_engine(model, warp_sim, batch):
    """Friction, mass, motor strength, CoM offset, latency and a push, per world."""
    inits, ctrl = batch
    worlds = [World(model),
              make_world(model, friction_scale=0.5, mass_scale=1.1, motor_scale=0.9,
                         com_offset_m=(0.01, -0.01, 0.0), latency_steps=3),
              make_world(model, push_ns=(0.0, 2.0, 0.0), push_time_s=0.3),
              make_world(model, push_ns=(0.0, -8.0, 0.0), push_time_s=0.2)]
    c = ctrl[1, :500]
    sc, dc = simulate_worlds(worlds, inits[1], c, 1, sensors=True)
    sw, dw = simulate_worlds(worlds, inits[1], c, 1, sensors=True, simulator=warp_sim)
    tc, tw = torso_track(sc), torso_track(sw)
    fall_c = fall_step(tc, nao.FALL_HEIGHT_M, nao.FALL_TILT_RAD) < 500
    fall_w = fall_step(tw, nao.FALL_HEIGHT_M, nao.FALL_TILT_RAD) < 500
    assert (fall_c == fall_w).all() and fall_c[3] and not fall_c[0]
    assert np.abs(sc[:, :EARLY, 1:8] - sw[:, :EARLY, 1:8]).max() < 1e-3
    # the worlds differ from each other (so the per-world fields and pushes were applied)
    assert np.abs(sw[1, 100:, 2] - sw[0, 100:, 2]).max() > 1e-3  # y under a lateral push...
    assert np.abs(sw[2, 100:, 2] - sw[0, 100:, 2]).max() > 1e-3
    late = ~fall_c
    d_c = tc.xyz[late, -1, :2] - tc.xyz[late, 0, :2]
    d_w = tw.xyz[late, -1, :2] - tw.xyz[late, 0, :2]
    assert np.linalg.norm(d_c - d_w, axis=1).max() < DISP_TOL_M


def test_one_perturbed_world_alone_keeps_its_fields(model, warp_sim, batch):
    """All trajectories in one heavy, weak, slippery world: no field differs between the
    worlds, but every one differs from the simulator's model, and must still be applied."""
    inits, ctrl = batch
    heavy = make_world(model, friction_scale=0.5, mass_scale=1.1, motor_scale=0.7)
    c = ctrl[1, :150]
    sc = simulate_worlds([heavy], inits[1], c, 1)
    sw = simulate_worlds([heavy], inits[1], c, 1, simulator=warp_sim)
    nominal = simulate_worlds([World(model)], inits[1], c, 1, simulator=warp_sim)
    err = np.abs(sc[:, :EARLY, 1:8] - sw[:, :EARLY, 1:8]).max()
    assert err < 1e-3
    assert np.abs(nominal[:, :EARLY, 1:8] - sw[:, :EARLY, 1:8]).max() > 10 * max(err, 1e-6)


def test_memory_is_estimated_before_allocation(model, warp_sim):
    small, big = warp_sim.memory(1024, 1000), warp_sim.memory(8192, 1000)
    assert 7.5 < big.needed / small.needed < 8.5  # linear in the worlds
    # per world: at least its recording (1000 steps x (22 + 58 + 6) floats) twice
    assert small.needed > 2 * 1024 * 1000 * 86 * 4
    assert big.device == "cpu" and big.free is not None


def test_unknown_device_and_bad_settings_are_one_line(model):
    with pytest.raises(InputError, match="problem.warp_device"):
        WarpSimulator(model, "tpu:7")
