"""humanoid-repertoire: the step encoding, the problem's measures against replay, pick and
walk-to planning, and a short run end to end."""

from __future__ import annotations

import json

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.leg_ik import leg_fk
from evomotion.studies.humanoid_repertoire import step
from evomotion.studies.humanoid_repertoire.artifacts import chain, ready_motion
from evomotion.studies.humanoid_repertoire.step_planning import plan


def test_every_step_starts_and_ends_in_the_ready_pose():
    rng = np.random.default_rng(0)
    ready = step.ready_pose()
    for g in rng.uniform(step.LOWER, step.UPPER, (20, len(step.GENES))):
        q = step.poses(g)
        np.testing.assert_allclose(q[0], ready, atol=1e-12)
        np.testing.assert_allclose(q[-1], ready, atol=1e-12)


def test_turning_step_turns_the_feet_as_planned_through_the_shared_hip_motor():
    """Both legs use the one hip yaw-pitch value, and the feet's yaw relative to each other
    (what the floor sees) follows the plan: 0 at the start, the full turn while the lead
    foot is down and the other is not yet, 0 again at the end."""
    g = step.DEFAULT.copy()
    g[step.INDEX["dtheta_rad"]] = 0.6
    q = step.poses(g)
    i_l, i_r = nao.JOINTS.index("LHipYawPitch"), nao.JOINTS.index("RHipYawPitch")
    np.testing.assert_array_equal(q[:, i_l], q[:, i_r])
    left = q[:, [nao.JOINTS.index(j) for j in nao.LEFT_LEG]]
    right = q[:, [nao.JOINTS.index(j) for j in nao.RIGHT_LEG]]
    _, Rl = leg_fk(left, left=True)
    _, Rr = leg_fk(right, left=False)
    rel = np.arctan2(Rl[..., 1, 0], Rl[..., 0, 0]) - np.arctan2(Rr[..., 1, 0], Rr[..., 0, 0])
    sh, sw = step.durations_ms(g)
    k = (2 * sh + sw) // step.POSE_MS  # after the first swing and the middle shift
    assert abs(rel[0]) < 1e-6 and abs(rel[-1]) < 1e-6
    assert abs(rel[k] - 0.6) < 0.02


def test_measures_are_what_replay_measures():
    from evomotion.sim.robots.nao.replay import simulate_motion
    from evomotion.studies.humanoid_repertoire.problem import (
        HumanoidRepertoireConfig,
        HumanoidRepertoireProblem,
    )

    p = HumanoidRepertoireProblem(HumanoidRepertoireConfig(hold_s=1.0, threads=1))
    g = step.DEFAULT.copy()
    g[:3] = [-0.05, 0.02, 0.2]
    ev = p.evaluate(np.stack([step.DEFAULT, g]))
    assert ev.measures.shape == (2, 3) and np.isfinite(ev.measures).all()
    assert ev.fitness[0] > -1.0  # the in-place step stands
    # the horizon of the problem is the longest step + hold: replay with the same length
    r = simulate_motion(p.motion(g), hold_s=1.0)["summary"]
    np.testing.assert_allclose(ev.measures[1, :2], r["displacement_m"], atol=1e-6)
    np.testing.assert_allclose(ev.measures[1, 2], np.degrees(r["heading_change_rad"]),
                               atol=1e-4)


def test_plan_finds_the_shortest_sequence():
    steps = np.array([[0.05, 0.0, 0.0], [0.0, 0.04, 0.0], [0.0, 0.0, 20.0],
                      [-0.03, 0.0, 0.0]])
    idx, pose = plan(steps, np.array([0.2, 0.08, 0.0]))
    assert sorted(idx) == [0, 0, 0, 0, 1, 1]
    np.testing.assert_allclose(pose, [0.2, 0.08, 0.0], atol=1e-9)
    idx, pose = plan(steps, np.array([0.0, 0.0, 60.0]))
    assert idx == [2, 2, 2]


def test_chain_and_ready_motion():
    r = ready_motion()
    np.testing.assert_allclose(r.values[-1], step.ready_pose())
    from evomotion.studies.humanoid_repertoire.problem import HumanoidRepertoireProblem

    p = HumanoidRepertoireProblem()
    a, b = p.motion(step.DEFAULT), p.motion(step.DEFAULT * 1.0)
    c = chain([a, b])
    assert len(c.times_ms) == len(a.times_ms) + len(b.times_ms) - 1
    assert np.all(np.diff(c.times_ms) == step.POSE_MS)


def test_short_run_writes_a_repertoire_that_pick_and_walk_to_use(tmp_path):
    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study
    from evomotion.studies import get_study
    from evomotion.studies.humanoid_repertoire.step_planning import pick, walk_to

    s = get_study("humanoid-repertoire")
    cfg = resolve_config(s, None, list(s.smoke) + ["run.generations=3"])
    res = run_study(s, cfg, tmp_path, quiet=True)
    assert res.exit_code == 0
    index = json.loads((tmp_path / "repertoire" / "index.json").read_text())
    assert index["entries"] and (tmp_path / "archive.npz").exists()
    for e in index["entries"]:
        assert (tmp_path / "repertoire" / e["file"]).exists()
    r = pick(tmp_path, 0.0, 0.0, 0.0)
    assert r["cell"] in [e["cell"] for e in index["entries"]]
    w = walk_to(tmp_path, 0.05, 0.0, 0.0, out=tmp_path / "chain.motion", hold_s=0.2)
    assert w["steps"] >= 1 and (tmp_path / "chain.motion").exists()
    with pytest.raises(InputError, match="run folder"):
        pick(tmp_path / "nothing", 0, 0, 0)
    with pytest.raises(InputError, match="finite"):
        pick(tmp_path, float("nan"), 0, 0)
    bad = tmp_path / "bad"
    (bad / "repertoire").mkdir(parents=True)
    (bad / "config.toml").write_text('study = "humanoid-repertoire"\n')
    (bad / "repertoire" / "index.json").write_text(
        '{"entries": [{"objective": 0, "file": "a.motion", "measured": {"dx_m": 0}}]}')
    with pytest.raises(InputError, match="index.json: entry 0"):
        pick(bad, 0, 0, 0)
