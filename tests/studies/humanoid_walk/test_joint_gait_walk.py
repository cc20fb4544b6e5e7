"""humanoid-walk-open-loop on other robots (``--robot``): the joint-space gait and the walk
problem."""

from __future__ import annotations

import importlib.util
import json

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.sim.robots import load_robot
from evomotion.studies import get_study
from evomotion.studies.humanoid_walk import joint_gait

HAS_DM = importlib.util.find_spec("dm_control") is not None


def test_gait_starts_at_the_pose_and_swings_the_legs_in_antiphase():
    robot = load_robot("op3")
    names, lo, hi, default = joint_gait.gene_table("biped")
    t = np.arange(0, 6.0, 0.004)
    inf = np.full(robot.model.nu, np.inf)
    q = joint_gait.targets(default[None], "biped", robot.gait, robot.pose, -inf, inf, t, 3.0)
    np.testing.assert_allclose(q[0, 0], robot.pose, atol=1e-12)  # amplitude and offsets 0
    (lc, ls), (rc, rs) = robot.gait["hip_pitch"]
    steady = (t > 2.5) & (t < 3.5)
    left = ls * (q[0, steady, lc] - q[0, steady, lc].mean())
    right = rs * (q[0, steady, rc] - q[0, steady, rc].mean())
    assert np.corrcoef(left, right)[0, 1] < -0.95  # antiphase
    amp = 0.5 * (left.max() - left.min())
    assert abs(amp - default[names.index("hip_amp_rad")]) < 0.01
    (kc, ks), _ = robot.gait["knee"]
    assert (ks * (q[0, :, kc] - robot.pose[kc]) >= -1e-12).all()  # the knee only flexes
    end = q[0, -1]  # after the walk: the pose plus the held crouch (no swing)
    assert abs(ks * (end[kc] - robot.pose[kc]) - default[names.index("crouch_rad")]) < 1e-9
    lo_c = robot.model.actuator_ctrlrange[:, 0]
    q2 = joint_gait.targets(hi[None], "biped", robot.gait, robot.pose, lo_c, -lo_c + 10, t, 3.0)
    assert (q2 >= lo_c - 1e-12).all()  # clipped to the actuator ranges


def test_walk_on_op3_in_perturbed_worlds(tmp_path):
    s = get_study("humanoid-walk-open-loop")
    over = [*s.smoke, "problem.robot=op3", "run.generations=1"]  # smoke: 2 worlds
    res = run_study(s, resolve_config(s, None, over), tmp_path / "r", quiet=True)
    assert res.generation == 1 and np.isfinite(res.best_fitness)
    best = json.loads((tmp_path / "r" / "best.json").read_text())
    assert best["robot"] == "op3" and set(best["gait"]) == set(joint_gait.gene_table("biped")[0])
    assert "straightness" in best["metrics"]
    replay = json.loads((tmp_path / "r" / "best_replay.json").read_text())
    assert replay["robot"] == "op3" and replay["gait_kind"] == "biped"
    assert "l_knee" in (tmp_path / "r" / "best.motion").read_text().splitlines()[0]
    assert "best gait on op3" in (tmp_path / "r" / "log.txt").read_text()


@pytest.mark.skipif(not HAS_DM, reason="dm_control is not installed")
def test_quadruped_trot_evaluates():
    s = get_study("humanoid-walk-open-loop")
    cfg = resolve_config(s, None, ["problem.robot=dm-quadruped", "problem.worlds=1",
                                   "problem.walk_s=1.0"])
    p = s.make_problem(cfg.problem)
    assert p.kind == "quadruped" and p.genome.dim == len(joint_gait.GENES["quadruped"])
    ev = p.evaluate(p.initial_population(3, np.random.default_rng(0)))
    assert np.isfinite(ev.fitness).all() and (ev.metrics["cost_of_transport"] >= 0).all()


def test_a_robot_without_gait_roles_is_refused(tmp_path):
    spec = tmp_path / "r.toml"
    text = (load_robot("op3").spec.path.read_text().split("[gait]")[0]
            .replace('mjcf = "evomotion:', 'mjcf = "evomotion:'))
    spec.write_text(text)
    s = get_study("humanoid-walk-open-loop")
    with pytest.raises(InputError, match=r"has no \[gait\] section"):
        s.make_problem(resolve_config(s, None, [f"problem.robot={spec}",
                                                "problem.worlds=1"]).problem)
