"""Perturbed worlds (sim/worlds.py) and the stress options of ``evomotion replay``."""

import json
import subprocess
import sys

import mujoco
import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.sim.motion import read_motion
from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.replay import (
    StressOptions,
    motion_targets,
    replay,
    start_state,
    stress_motion,
)
from evomotion.sim.rollout import BatchSimulator
from evomotion.sim.worlds import (
    Perturbation,
    delayed_controls,
    draw_worlds,
    make_world,
    simulate_worlds,
)
from fixture_files import WEBOTS_MOTIONS

FIXTURES = WEBOTS_MOTIONS
HANDWAVE = FIXTURES / "HandWave.motion"


@pytest.fixture(scope="module")
def base():
    return nao.load_model()


@pytest.fixture(scope="module")
def handwave(base):
    motion = read_motion(HANDWAVE)
    dt = base.opt.timestep
    nstep = int(np.ceil((motion.duration_s + 1.0) / dt))
    first, ctrl = motion_targets(motion, dt, nstep)
    return motion, nao.initial_state(base, first), ctrl


def _arrays(world):
    m = world.model
    return [m.geom_friction, m.body_mass, m.body_inertia, m.body_ipos, m.actuator_gainprm,
            m.actuator_biasprm, m.actuator_forcerange]


def test_worlds_are_deterministic_in_the_seed(base):
    a = draw_worlds(base, Perturbation(), 4, np.random.default_rng(7), 1.4)
    b = draw_worlds(base, Perturbation(), 4, np.random.default_rng(7), 1.4)
    c = draw_worlds(base, Perturbation(), 4, np.random.default_rng(8), 1.4)
    for wa, wb in zip(a, b, strict=True):
        assert wa.params == wb.params
        for x, y in zip(_arrays(wa), _arrays(wb), strict=True):
            np.testing.assert_array_equal(x, y)
    assert [w.params for w in a] != [w.params for w in c]
    for w in a:  # inside the documented ranges
        p = w.params
        assert 0.5 <= p["friction_scale"] <= 1.4 and 0 <= p["latency_steps"] <= 10
        assert abs(p["push_ns"][1]) <= 2.5 and 0.35 <= p["push_time_s"] <= 1.05
        assert max(abs(v) for v in p["com_offset_m"]) <= 0.02


def test_pinning_a_range_keeps_the_other_draws(base):
    a = draw_worlds(base, Perturbation(), 3, np.random.default_rng(1), 1.0)
    b = draw_worlds(base, Perturbation(friction_scale=(0.4, 0.4)), 3,
                    np.random.default_rng(1), 1.0)
    assert all(w.params["friction_scale"] == 0.4 for w in b)
    for wa, wb in zip(a, b, strict=True):
        np.testing.assert_array_equal(wa.model.body_mass, wb.model.body_mass)
        assert wa.params["push_ns"] == wb.params["push_ns"]


def test_identity_world_is_exactly_the_unperturbed_rollout(base, handwave):
    _, init, ctrl = handwave
    ctrl = ctrl[:200]
    with BatchSimulator(base, 1) as sim:
        ref = sim.run(init, ctrl[None])[0]
    w = make_world(base)
    states = simulate_worlds([w, w], init, ctrl, nthread=2)
    np.testing.assert_array_equal(states[0], ref)
    np.testing.assert_array_equal(states[1], ref)


def test_scales_edit_the_model_arrays(base):
    w = make_world(base, friction_scale=0.5, mass_scale=1.2, motor_scale=0.9,
                   com_offset_m=(0.01, 0.0, 0.0))
    m = w.model
    np.testing.assert_allclose(m.geom_friction, 0.5 * base.geom_friction)
    np.testing.assert_array_equal(base.geom_friction, nao.load_model().geom_friction)
    np.testing.assert_allclose(m.body_mass, 1.2 * base.body_mass)
    np.testing.assert_allclose(m.body_subtreemass[0], 1.2 * nao.TOTAL_MASS_KG, rtol=1e-3)
    np.testing.assert_allclose(m.actuator_gainprm[:, 0], 0.9 * base.actuator_gainprm[:, 0])
    np.testing.assert_allclose(m.actuator_biasprm[:, 1], -m.actuator_gainprm[:, 0])
    np.testing.assert_allclose(m.actuator_forcerange, 0.9 * base.actuator_forcerange)
    torso = base.body("torso").id
    np.testing.assert_allclose(m.body_ipos[torso] - base.body_ipos[torso], [0.01, 0, 0])


def test_latency_delays_controls_holding_the_first_target():
    ctrl = np.arange(5.0)[:, None] * np.ones((1, 2))
    out = delayed_controls(ctrl, np.array([0, 2]))
    np.testing.assert_array_equal(out[0, :, 0], [0, 1, 2, 3, 4])
    np.testing.assert_array_equal(out[1, :, 0], [0, 0, 0, 1, 2])


def test_push_changes_the_momentum_by_the_impulse(handwave):
    _, init, ctrl = handwave
    m = nao.load_model()
    m.opt.gravity[:] = 0.0
    init = init.copy()
    init[nao.STATE_QPOS_OFFSET + 2] += 1.0  # free-floating, 1 m above the floor
    w = make_world(m, push_ns=(0.0, 1.5, 0.0), push_time_s=0.1)
    states = simulate_worlds([w], init, ctrl[:60])[0]
    d = mujoco.MjData(m)

    def momentum(state):
        mujoco.mj_setState(m, d, state, nao.STATE_SPEC)
        mujoco.mj_forward(m, d)
        mujoco.mj_subtreeVel(m, d)
        return d.subtree_linvel[1] * m.body_subtreemass[1]

    np.testing.assert_allclose(momentum(states[40]) - momentum(states[10]), [0, 1.5, 0],
                               atol=2e-3)


def test_large_push_makes_hand_wave_fall(handwave, base):
    motion, init, ctrl = handwave
    worlds = [make_world(base, push_ns=(0.0, j, 0.0), push_time_s=motion.duration_s / 2)
              for j in (0.0, 8.0)]
    z = simulate_worlds(worlds, init, ctrl, nthread=2)[:, -1, nao.STATE_QPOS_OFFSET + 2]
    assert z[0] > 0.28 and z[1] < nao.FALL_HEIGHT_M
    calm = replay(HANDWAVE, stress=StressOptions(push_ns=0.0))
    pushed = replay(HANDWAVE, stress=StressOptions(push_ns=-8.0))
    assert not calm["fell"] and pushed["fell"] and pushed["displacement_m"][1] < -0.1


def test_stress_with_unit_values_matches_the_plain_replay():
    plain = replay(HANDWAVE)
    same = replay(HANDWAVE, stress=StressOptions(friction=1.0, mass_scale=1.0))
    assert same == plain


def test_trials_json_keys_from_the_command_line():
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "replay",
                        str(FIXTURES / "TurnLeft40.motion"), "--trials", "8", "--seed", "1",
                        "--json"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert set(out) == {"displacement_m", "heading_change_rad", "fell", "fall_time_s",
                        "trials", "fall_rate", "forward_mean_m", "forward_min_m"}
    assert out["trials"] == 8 and 0.0 <= out["fall_rate"] <= 1.0
    assert out["forward_min_m"] <= out["forward_mean_m"]


def test_face_down_start_rests_on_the_floor_and_hand_wave_stays_down(base, handwave):
    motion, _, _ = handwave
    first, _ = motion_targets(motion, base.opt.timestep, 1)
    state = start_state(base, first, "face-down")
    d = mujoco.MjData(base)
    mujoco.mj_setState(base, d, state, nao.STATE_SPEC)
    mujoco.mj_forward(base, d)
    assert d.body("torso").xmat.reshape(3, 3)[2, 0] == pytest.approx(-1.0)  # front down
    assert all(c.dist > -1e-6 for c in d.contact[:d.ncon])  # resting, not sunk
    out = stress_motion(motion, StressOptions(start="face-down"))["summary"]
    assert out["ended_upright"] is False and out["fell"] is False


@pytest.mark.parametrize("opts,msg", [
    (StressOptions(friction=-1.0), "--friction: expected a value in (0.0, 100.0]"),
    (StressOptions(mass_scale=0.0), "--mass-scale: expected a value in (0.0, 100.0]"),
    (StressOptions(mass_scale=1e300), "--mass-scale: expected a value in (0.0, 100.0]"),
    (StressOptions(push_ns=float("nan")), "--push: expected a finite number"),
    (StressOptions(push_ns=51.0), "--push: expected a value in [-50.0, 50.0]"),
    (StressOptions(trials=0), "--trials: expected a value in [1, 1000]"),
    (StressOptions(trials=2, seed=-3), "--seed: expected >= 0"),
    (StressOptions(start="sideways"), "--from: expected one of standing"),
])
def test_bad_stress_values_are_one_line_errors(opts, msg):
    with pytest.raises(InputError) as e:
        opts.validate()
    assert msg in str(e.value) and "\n" not in str(e.value)


def test_bad_perturbation_ranges_are_errors(base):
    with pytest.raises(InputError, match="friction_scale"):
        Perturbation(friction_scale=(1.2, 0.8)).validate()
    with pytest.raises(InputError, match="mass_scale"):
        Perturbation(mass_scale=(-1.0, 1.0)).validate()
    with pytest.raises(InputError, match="latency_steps"):
        draw_worlds(base, Perturbation(latency_steps=(0, 2.5)), 1, np.random.default_rng(), 1.0)
    with pytest.raises(InputError, match="hold"):
        replay(HANDWAVE, hold_s=-1.0)


def test_latin_worlds_put_one_world_in_each_stratum(base):
    k = 8
    ws = draw_worlds(base, Perturbation(), k, np.random.default_rng(3), 4.0, design="latin")
    f = np.array([w.params["friction_scale"] for w in ws])
    strata = np.floor((f - 0.5) / (1.4 - 0.5) * k).astype(int)
    assert sorted(strata.tolist()) == list(range(k))
    push = np.array([w.push_ns[1] for w in ws])
    assert sorted(np.floor((push + 2.5) / 5.0 * k).astype(int).tolist()) == list(range(k))
    lat = np.array([w.latency_steps for w in ws])
    assert lat.min() >= 0 and lat.max() <= 10
    again = draw_worlds(base, Perturbation(), k, np.random.default_rng(3), 4.0, design="latin")
    assert [w.params for w in again] == [w.params for w in ws]
    with pytest.raises(InputError, match="design"):
        draw_worlds(base, Perturbation(), k, np.random.default_rng(3), 4.0, design="sobol")


def test_early_stop_keeps_the_standing_worlds_and_freezes_the_fallen(base, handwave):
    _, init, ctrl = handwave
    ctrl = ctrl[:300]
    calm = make_world(base)
    shove = make_world(base, push_ns=(0.0, 12.0, 0.0), push_time_s=0.2)
    full = simulate_worlds([calm, shove], init, ctrl, nthread=1)

    def fell(states):
        return states[:, :, nao.STATE_QPOS_OFFSET + 2] < 0.28

    part = simulate_worlds([calm, shove], init, ctrl, nthread=1,
                           stopped=lambda s: fell(s).any(axis=1), segment_steps=50)
    np.testing.assert_allclose(part[0], full[0], atol=1e-8)
    first = int(np.argmax(fell(full[1:])[0]))
    stop = (first // 50 + 1) * 50  # the end of the segment in which it fell
    assert fell(full[1:])[0].any() and stop < 300
    np.testing.assert_allclose(part[1, :stop], full[1, :stop], atol=1e-8)
    np.testing.assert_array_equal(part[1, stop:], np.repeat(part[1, stop - 1][None],
                                                            300 - stop, axis=0))


def test_pushes_scale_with_each_robots_mass():
    """The default push range is the NAO's (5.3054 kg, unchanged); another robot's is scaled
    by its mass (the same change of velocity)."""
    from evomotion.sim.robots import load_robot
    from evomotion.sim.worlds import PUSH_REFERENCE_MASS_KG, Perturbation

    p = Perturbation(push_ns=(-3.5, 3.5))
    nao_robot, op3 = load_robot("nao"), load_robot("op3")
    assert nao_robot.mass_kg == PUSH_REFERENCE_MASS_KG and p.for_mass(nao_robot.mass_kg) is p
    lo, hi = p.for_mass(op3.mass_kg).push_ns
    assert hi == -lo == 3.5 * op3.mass_kg / PUSH_REFERENCE_MASS_KG
    assert op3.mass_kg == float(op3.model.body_mass.sum())  # no published mass: the model's
