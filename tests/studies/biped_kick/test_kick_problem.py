"""Kick motion, scene, problem (aims, constraints), keyframe baseline, tiny experiment."""

from __future__ import annotations

import mujoco
import numpy as np

from evomotion.core.constraints import feasibility_first
from evomotion.errors import InputError
from evomotion.sim.motion import format_motion, parse_motion
from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.joint_limits import check_speeds
from evomotion.sim.zmp import centre_of_pressure, floor_contacts
from evomotion.studies.biped_kick import scene
from evomotion.studies.biped_kick.experiment import on_grid, run_experiment
from evomotion.studies.biped_kick.keyframe import keyframe_kicks, kicking_foot, shoot_motion
from evomotion.studies.biped_kick.motion import (
    GENE_INDEX,
    GENES,
    KEY_S,
    SETTLE_S,
    START,
    execution_time_s,
    foot_trajectories,
    joint_targets,
    key_times,
    kick_motion,
    limit_excess,
    rest_pose,
)
from evomotion.studies.biped_kick.problem import (
    FLOOR_M,
    KickConfig,
    KickProblem,
    support_margin_batch,
)

LO = np.array([g[1] for g in GENES])
HI = np.array([g[2] for g in GENES])
X0 = np.array([START[g[0]] for g in GENES])


def test_foot_trajectory_phases_and_aim():
    g = ((LO + HI) / 2)[None]
    ts, tl, tk, tr = (g[0, GENE_INDEX[k]] for k in ("t_shift_s", "t_lift_s", "t_kick_s",
                                                     "t_retract_s"))
    times = np.array([0.1, SETTLE_S + ts + tl - 1e-9, SETTLE_S + ts + tl + tk - 1e-9,
                      SETTLE_S + execution_time_s(g)[0] + 0.1])
    _, l0, r0 = rest_pose()
    rest = r0 - np.array([0, g[0, GENE_INDEX["shift_y_m"]], 0])
    for aim in (0.0, 0.4):
        feet = foot_trajectories(g, times, aim)
        phi = g[0, GENE_INDEX["aim_swing"]] * aim
        u = np.array([np.cos(phi), np.sin(phi), 0.0])
        up = np.array([0, g[0, GENE_INDEX["kick_y_m"]], 0])
        lift = rest + up + [0, 0, g[0, GENE_INDEX["lift_z_m"]]] + g[0, GENE_INDEX["lift_x_m"]] * u
        kick = rest + up + [0, 0, g[0, GENE_INDEX["kick_z_m"]]] + g[0, GENE_INDEX["kick_x_m"]] * u
        assert np.allclose(feet["right"][0, 0], r0) and np.allclose(feet["left"][0, 0], l0)
        assert np.allclose(feet["right"][0, 1], lift, atol=1e-6)
        assert np.allclose(feet["right"][0, 2], kick, atol=1e-6)
        assert np.allclose(feet["right"][0, 3], r0) and np.allclose(feet["left"][0, 3], l0)
    ctrl = joint_targets(np.vstack([g, LO, HI]), np.arange(1, 800) * 0.004)
    assert ctrl.shape == (3, 799, 22) and np.all(np.isfinite(ctrl))


def test_kick_motion_is_the_simulated_key_poses():
    m = kick_motion(X0, np.radians(20))
    assert m.joints == nao.JOINTS and np.all(np.diff(m.times_ms) == 1000 * KEY_S)
    kt = key_times(X0[None])
    assert np.array_equal(m.values, joint_targets(X0[None], kt, np.radians(20))[0])
    again = parse_motion(format_motion(m))
    assert np.allclose(again.values, m.values, atol=1e-5)
    assert m.duration_s >= SETTLE_S + execution_time_s(X0[None])[0] - 1e-9


def test_limit_excess_matches_the_export_check():
    fast = X0.copy()
    fast[GENE_INDEX["t_kick_s"]] = 0.06
    fast[GENE_INDEX["kick_x_m"]] = 0.16
    keys = np.stack([kick_motion(x).values for x in (fast,)])
    _, excess, ratio = limit_excess(keys)
    assert ratio[0] > 1 and excess[0] > 0
    try:
        check_speeds(kick_motion(fast))
        raise AssertionError("the export check passed a kick that is too fast")
    except ValueError as exc:
        assert "rad/s" in str(exc)


def test_scene_ball_and_rolling():
    m = scene.load_scene()
    assert np.isclose(m.body("ball").mass[0], scene.BALL_MASS_KG)
    assert np.isclose(m.geom("ball").size[0], 0.05) and m.geom("ball").condim[0] == 6
    a = scene.measured_deceleration(0.005)
    assert 0.8 * scene.rolling_deceleration(0.005) < a < 1.1 * scene.rolling_deceleration(0.005)


def test_carpet_is_calibrated_to_the_cited_deceleration():
    """The default carpet decelerates the ball by B-Human's 0.35 m/s^2 (within 1 %), and the
    calibration finds that friction again; a kick's default config uses it."""
    assert abs(scene.measured_deceleration() / scene.CARPET_DECELERATION_M_S2 - 1) < 0.01
    assert abs(scene.calibrated_rolling_m() / scene.CARPET_ROLLING_M - 1) < 0.01
    assert abs(scene.calibrated_rolling_m(0.7) / 0.005 - 1) < 0.02  # the old assumption
    assert KickConfig().rolling_m == scene.CARPET_ROLLING_M


def test_sensor_cop_matches_contact_cop_when_standing():
    m = scene.load_scene()
    d = mujoco.MjData(m)
    mujoco.mj_setState(m, d, scene.initial_scene_state(m, scene.default_ball_xy(m)),
                       nao.STATE_SPEC)
    d.ctrl[:] = nao.pose_vector()
    for _ in range(150):
        mujoco.mj_step(m, d)
    cop, total = centre_of_pressure(*floor_contacts(m, d, m.geom("floor").id))
    sl = scene.sensor_slices(m)
    margin = support_margin_batch(d.sensordata[None].copy(), sl)[0]
    fz = [abs(d.sensordata[sl[f"{s}_contact"]][3]) for s in "lr"]
    pts = [d.sensordata[sl[f"{s}_contact"]][4:6] for s in "lr"]
    cop_sensor = (fz[0] * pts[0] + fz[1] * pts[1]) / (fz[0] + fz[1])
    assert np.linalg.norm(cop_sensor - cop) < 5e-3
    assert abs(sum(fz) - total) < 0.05 * total
    assert 0.03 < margin < 0.08


def test_kick_problem_feasibility_first():
    p = KickProblem(KickConfig(nthread=2, aims_deg=(-20.0, 0.0, 20.0)))
    rng = np.random.default_rng(0)
    X = np.vstack([X0, rng.uniform(LO, HI, (2, len(LO)))])
    ev = p.evaluate(X)
    m = ev.metrics
    assert ev.fitness.shape == (3,) and np.all(np.isfinite(ev.fitness))
    assert set(m) == set(p.metric_names)
    assert np.allclose(m["exec_time_s"], execution_time_s(X))
    feasible = m["violation"] <= 0
    assert np.array_equal(feasible, m["feasible"] > 0)
    assert np.all(ev.fitness[~feasible] < FLOOR_M) and np.all(ev.fitness[feasible] >= FLOOR_M)
    # the violation counts falls, ZMP deficit and the NAO's limits
    assert np.all((m["violation"] > 0) >= ((m["fell"] > 0) | (m["zmp_deficit_mm_s"] > 0)
                                          | (m["speed_ratio"] > 1)))
    assert np.allclose(ev.fitness, feasibility_first(ev.fitness, m["violation"], "max",
                                                      FLOOR_M))
    for i in range(3):  # deterministic and independent of the rest of the batch
        assert p.evaluate(X[i:i + 1]).fitness[0] == ev.fitness[i]


def test_aims_move_the_ball_place_and_initial_population():
    p = KickProblem(KickConfig(nthread=1))
    g = np.repeat(X0[None], 2, axis=0)
    b = p.ball_xy(g, np.radians([-20.0, 20.0]))
    assert b[1, 1] - b[0, 1] > 0  # aim left: the ball lies further left on the foot
    pop = p.initial_population(5, np.random.default_rng(1))
    assert np.array_equal(pop[0], X0) and pop.shape == (5, len(GENES))
    assert np.all((pop >= LO) & (pop <= HI))


def test_keyframe_baseline_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the shipped Shoot.motion, wherever the run starts
    assert kicking_foot(shoot_motion()) in ("l", "r")
    r = keyframe_kicks(np.zeros((1, 2)))
    assert np.isfinite(r["distance_m"][0]) and r["exec_time_s"][0] > 1.0
    assert r["min_margin_m"][0] < 0.1


def test_tiny_experiment(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    res = run_experiment(tmp_path, seeds=1, budget=8, kicks=2, variants=["cmaes"],
                         cfg=KickConfig(aims_deg=(0.0,)), log=lambda s: None)
    for f in ("curves.npz", "convergence.png", "results.json", "table.md"):
        assert (tmp_path / f).exists()
    row = res["optimisers"]["cmaes"]
    assert row["straight"]["n"] == 2 and row["aimed"] == {}  # one aim trained: no accuracy
    assert "keyframe" in (tmp_path / "table.md").read_text()
    assert np.array_equal(on_grid(np.array([12, 24]), np.array([1.0, 2.0]),
                                  np.array([5, 12, 30])), [np.nan, 1.0, 2.0], equal_nan=True)


def test_kicks_in_perturbed_worlds_keep_the_carpet():
    """Kick worlds perturb the robot (friction, masses, motors, latency) but not the ball's
    calibrated roll; the nominal world reproduces the nominal kick exactly, and a world's kick
    does not depend on the other kicks of its batch."""
    from evomotion.sim.worlds import World
    from evomotion.studies.biped_kick.experiment import kick_worlds, perturbed_kicks

    p = KickProblem(KickConfig(nthread=1, aims_deg=(0.0,)))
    worlds = kick_worlds(p, 3, np.random.default_rng(4))
    ball, floor = p.model.geom("ball").id, p.model.geom("floor").id
    for w in worlds:
        assert np.array_equal(w.model.geom_friction[ball], p.model.geom_friction[ball])
        assert w.push_ns == (0.0, 0.0, 0.0)
    assert len({float(w.model.geom_friction[floor, 0]) for w in worlds}) == 3
    offsets = np.zeros((2, 2))
    nominal = perturbed_kicks(p, X0, offsets)
    same = perturbed_kicks(p, X0, offsets, worlds=[World(p.model), worlds[0]])
    assert same["distance_m"][0] == nominal["distance_m"][0]
    alone = perturbed_kicks(p, X0, offsets[:1], worlds=worlds[:1])
    assert alone["distance_m"][0] == same["distance_m"][1] != nominal["distance_m"][0]
    try:
        perturbed_kicks(p, X0, offsets, worlds=worlds[:1])
        raise AssertionError("one world for two kicks was accepted")
    except InputError as exc:
        assert "one world per kick" in str(exc)


def test_tolerant_offset_is_the_centre_of_the_band_the_kick_tolerates():
    from evomotion.studies.biped_kick.experiment import perturbed_kicks, tolerant_offset

    p = KickProblem(KickConfig(nthread=1, aims_deg=(0.0,)))
    step = 0.0025
    c = tolerant_offset(p, X0, step_m=step)
    assert -0.03 <= c <= 0.03
    dy = np.arange(-0.03, 0.03 + step / 2, step)
    err = np.abs(perturbed_kicks(p, X0, np.stack([np.zeros_like(dy), dy], 1))["angle_error_deg"])
    ok = err <= 3.0
    assert ok.any() and ok[np.argmin(np.abs(dy - c))]  # inside the band it names
    assert tolerant_offset(p, X0, max_error_deg=-1.0) == 0.0  # no band: no offset


def test_the_checks_draw_scales_one_offset_draw_and_gives_a_world_per_offset():
    from evomotion.studies.biped_kick.experiment import kick_draw

    p = KickProblem(KickConfig(nthread=1, aims_deg=(0.0,)))
    a, wa = kick_draw(p, 4, (3, 4))
    b, wb = kick_draw(p, 4, (3, 4), spread_m=0.03)
    assert a.shape == (4, 2) and np.abs(a).max() <= 0.02 and len(wa) == len(wb) == 4
    assert np.allclose(b, a * 1.5) and not np.array_equal(a, kick_draw(p, 4, (5, 4))[0])
    floor = p.model.geom("floor").id
    assert [w.model.geom_friction[floor, 0] for w in wa] == \
        [w.model.geom_friction[floor, 0] for w in wb]
