"""Kick motion, scene, problem, keyframe baseline and a tiny end-to-end experiment."""

from __future__ import annotations

import mujoco
import numpy as np

from evomotion.sim import nao
from evomotion.studies.biped_kick import scene
from evomotion.studies.biped_kick.experiment import on_grid, run_experiment
from evomotion.studies.biped_kick.keyframe import keyframe_kicks, kicking_foot, shoot_motion
from evomotion.studies.biped_kick.motion import (
    GENE_INDEX,
    GENES,
    SETTLE_S,
    execution_time_s,
    foot_trajectories,
    joint_targets,
    rest_pose,
)
from evomotion.studies.biped_kick.problem import KickConfig, KickProblem, support_margin_batch
from evomotion.studies.biped_kick.zmp import centre_of_pressure, floor_contacts

LO = np.array([g[1] for g in GENES])
HI = np.array([g[2] for g in GENES])


def test_foot_trajectory_phases():
    g = ((LO + HI) / 2)[None]
    ts, tl, tk, tr = (g[0, GENE_INDEX[k]] for k in ("t_shift_s", "t_lift_s", "t_kick_s",
                                                     "t_retract_s"))
    times = np.array([0.1, SETTLE_S + ts + tl - 1e-9, SETTLE_S + ts + tl + tk - 1e-9,
                      SETTLE_S + execution_time_s(g)[0] + 0.1])
    feet = foot_trajectories(g, times)
    _, l0, r0 = rest_pose()
    rest = r0 - np.array([0, g[0, GENE_INDEX["shift_y_m"]], 0])
    lift = rest + g[0, [GENE_INDEX["lift_x_m"], GENE_INDEX["kick_y_m"], GENE_INDEX["lift_z_m"]]]
    kick = rest + g[0, [GENE_INDEX["kick_x_m"], GENE_INDEX["kick_y_m"], GENE_INDEX["kick_z_m"]]]
    assert np.allclose(feet["right"][0, 0], r0) and np.allclose(feet["left"][0, 0], l0)
    assert np.allclose(feet["right"][0, 1], lift, atol=1e-6)
    assert np.allclose(feet["right"][0, 2], kick, atol=1e-6)
    assert np.allclose(feet["right"][0, 3], r0) and np.allclose(feet["left"][0, 3], l0)
    ctrl = joint_targets(np.vstack([g, LO, HI]), np.arange(1, 800) * 0.004)
    assert ctrl.shape == (3, 799, 22) and np.all(np.isfinite(ctrl))
    # no jumps between physics steps for a moderate kick (fast kicks move ~0.4 rad per step)
    assert np.max(np.abs(np.diff(ctrl[0], axis=0))) < 0.1


def test_scene_ball_and_rolling():
    m = scene.load_scene()
    ball = m.body("ball")
    assert np.isclose(ball.mass[0], scene.BALL_MASS_KG)
    assert np.isclose(m.geom("ball").size[0], 0.05) and m.geom("ball").condim[0] == 6
    a = scene.measured_deceleration()
    assert 0.8 * scene.rolling_deceleration(0.005) < a < 1.1 * scene.rolling_deceleration(0.005)


def test_sensor_cop_matches_contact_cop_when_standing():
    m = scene.load_scene()
    d = mujoco.MjData(m)
    mujoco.mj_setState(m, d, scene.initial_scene_state(m, scene.default_ball_xy(m)),
                       nao.STATE_SPEC)
    d.ctrl[:] = nao.pose_vector()  # the state does not include the controls
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
    assert 0.03 < margin < 0.08  # both soles down: CoP well inside


def test_kick_problem_batch():
    p = KickProblem(KickConfig(nthread=2))
    rng = np.random.default_rng(0)
    X = rng.uniform(LO, HI, (3, len(LO)))
    ev = p.evaluate(X)
    assert ev.fitness.shape == (3,) and np.all(np.isfinite(ev.fitness))
    assert set(ev.metrics) == set(p.metric_names)
    assert np.allclose(ev.metrics["exec_time_s"], execution_time_s(X))
    m = ev.metrics
    expected = (m["distance_m"] - 0.5 * np.abs(m["lateral_m"]) - 3.0 * m["fell"]
                - 2.0 * m["zmp_violation"])
    assert np.allclose(ev.fitness, expected)
    for i in range(3):  # deterministic and independent of the rest of the batch
        again = p.evaluate(X[i:i + 1])
        assert again.fitness[0] == ev.fitness[i]


def test_keyframe_baseline_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the shipped Shoot.motion, wherever the run starts
    assert kicking_foot(shoot_motion()) in ("l", "r")
    r = keyframe_kicks(np.zeros((1, 2)))
    assert np.isfinite(r["distance_m"][0]) and r["exec_time_s"][0] > 1.0


def test_tiny_experiment(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    res = run_experiment(tmp_path, seeds=1, budget=12, kicks=2, variants=["cmaes"],
                         log=lambda s: None)
    for f in ("curves.npz", "convergence.png", "results.json", "table.md"):
        assert (tmp_path / f).exists()
    assert res["optimised_kick"]["n"] == 2
    assert np.array_equal(on_grid(np.array([12, 24]), np.array([1.0, 2.0]),
                                  np.array([5, 12, 30])), [np.nan, 1.0, 2.0], equal_nan=True)
