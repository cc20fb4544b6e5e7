"""The walk problem: evaluation is the replay of the exported motion; fitness ordering."""

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.sim.robots.nao.replay import simulate_motion
from evomotion.studies.humanoid_walk import foot_gait
from evomotion.studies.humanoid_walk.problem import (
    HumanoidWalkConfig,
    HumanoidWalkProblem,
    soft_floor,
)

SHORT = HumanoidWalkConfig(walk_s=1.0, hold_s=0.5, threads=1)


@pytest.fixture(scope="module")
def problem():
    return HumanoidWalkProblem(SHORT)


def test_evaluation_is_the_replay_of_the_motion(problem):
    g = foot_gait.DEFAULT
    ev = problem.evaluate(g[None])
    motion = problem.motion(g)
    hold = problem.horizon_s - motion.duration_s
    s = simulate_motion(motion, hold_s=hold)["summary"]
    assert ev.metrics["fell"][0] == float(s["fell"]) == 0.0
    assert ev.metrics["forward_m"][0] == pytest.approx(s["displacement_m"][0], abs=1e-6)
    assert ev.metrics["lateral_m"][0] == pytest.approx(s["displacement_m"][1], abs=1e-6)
    assert ev.metrics["heading_change_rad"][0] == pytest.approx(s["heading_change_rad"],
                                                               abs=1e-6)


def test_fitness_orders_fallen_too_fast_and_good_walks(problem):
    fast = foot_gait.DEFAULT.copy()
    fast[foot_gait.INDEX["period_s"]] = foot_gait.LOWER[foot_gait.INDEX["period_s"]]
    fast[foot_gait.INDEX["step_length_m"]] = foot_gait.UPPER[foot_gait.INDEX["step_length_m"]]
    fast[foot_gait.INDEX["step_height_m"]] = foot_gait.UPPER[foot_gait.INDEX["step_height_m"]]
    wild = foot_gait.DEFAULT.copy()
    wild[foot_gait.INDEX["lean_rad"]] = foot_gait.UPPER[foot_gait.INDEX["lean_rad"]]
    wild[foot_gait.INDEX["sway_m"]] = foot_gait.UPPER[foot_gait.INDEX["sway_m"]]
    wild[foot_gait.INDEX["sway_phase_rad"]] = foot_gait.UPPER[foot_gait.INDEX["sway_phase_rad"]]
    wild[foot_gait.INDEX["x_offset_m"]] = foot_gait.UPPER[foot_gait.INDEX["x_offset_m"]]
    ev = problem.evaluate(np.stack([foot_gait.DEFAULT, fast, wild]))
    f, m = ev.fitness, ev.metrics
    h = problem.horizon_s
    assert m["fell"][0] == 0 and m["speed_ratio"][0] <= 1 and f[0] > h + 0.01
    if m["speed_ratio"][1] > 1 and m["fell"][1] == 0:
        assert h <= f[1] < h + 0.51 < f[0]
    if m["fell"][2]:
        assert f[2] < h < f[0]
        assert f[2] == pytest.approx(m["time_to_fall_s"][2]
                                     + 0.1 * np.clip(m["forward_m"][2], -0.5, 0.5))


def test_soft_floor_is_increasing_and_bounded():
    q = np.linspace(-20, 3, 1000)
    v = soft_floor(q)
    assert np.all(np.diff(v) > 0) and v.min() > -0.99
    np.testing.assert_array_equal(v[q >= 0], q[q >= 0])


def test_initial_population_starts_at_the_default(problem):
    x = problem.initial_population(5, np.random.default_rng(0))
    assert x.shape == (5, foot_gait.LOWER.size)
    np.testing.assert_array_equal(x[0], foot_gait.DEFAULT)
    assert problem.initial_population(0, np.random.default_rng(0)).shape == (1, 14)


def test_worlds_evaluate_every_world_and_aggregate():
    p = HumanoidWalkProblem(HumanoidWalkConfig(walk_s=0.5, hold_s=0.2, threads=1, worlds=3,
                                               world_seed=1))
    ev = p.evaluate(np.stack([foot_gait.DEFAULT, foot_gait.DEFAULT]))
    assert ev.fitness.shape == (2,) and ev.fitness[0] == ev.fitness[1]
    assert 0.0 <= ev.metrics["fall_rate"][0] <= 1.0


@pytest.mark.parametrize("key,value", [("walk_s", 0.0), ("worlds", 0), ("speed_margin", 1.5),
                                       ("world_aggregate", "median"), ("hold_s", -1.0),
                                       ("segment_s", 0.0)])
def test_bad_config_is_one_line(key, value):
    import dataclasses

    with pytest.raises(InputError) as e:
        dataclasses.replace(HumanoidWalkConfig(), **{key: value}).validate()
    assert f"problem.{key}" in str(e.value) and "\n" not in str(e.value)


def test_worlds_give_the_same_result_whatever_the_batch_split():
    """Evaluators split a population into chunks: a genome's evaluation in K pushed worlds
    must not depend on the other genomes of its batch (bit for bit)."""
    p = HumanoidWalkProblem(HumanoidWalkConfig(walk_s=0.5, hold_s=0.2, threads=2, worlds=4,
                                               world_seed=3))
    x = p.initial_population(4, np.random.default_rng(1))
    whole = p.evaluate(x)
    parts = [p.evaluate(x[:1]), p.evaluate(x[1:3]), p.evaluate(x[3:])]
    np.testing.assert_array_equal(whole.fitness, np.concatenate([e.fitness for e in parts]))
    for k in whole.metrics:
        np.testing.assert_array_equal(whole.metrics[k],
                                      np.concatenate([e.metrics[k] for e in parts]))
