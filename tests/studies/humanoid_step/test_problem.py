import dataclasses

import numpy as np
import pytest

from evomotion.studies.humanoid_step.problem import HumanoidStepConfig, HumanoidStepProblem


@pytest.fixture(scope="module")
def problem():
    cfg = HumanoidStepConfig(intervals=4, motion_s=0.6, hold_s=0.4, threads=2, fitness="paper")
    return HumanoidStepProblem(cfg)


@pytest.fixture(scope="module")
def step_problem():
    cfg = HumanoidStepConfig(intervals=4, motion_s=0.6, hold_s=0.4, threads=2)
    return HumanoidStepProblem(cfg)


def _still(problem, n=1):
    """Genomes whose knots all equal the initial pose."""
    return np.tile(np.repeat(problem.encoding.q0, problem.cfg.intervals - 1), (n, 1))


def test_standing_still_survives_with_no_distance(problem):
    ev = problem.evaluate(_still(problem))
    assert ev.metrics["fell"][0] == 0.0
    assert ev.metrics["time_to_fall_s"][0] == pytest.approx(1.0)
    assert abs(ev.metrics["forward_m"][0]) < 0.005
    assert ev.fitness[0] == pytest.approx(1.0 + 10.0 * ev.metrics["forward_m"][0])
    assert ev.metrics["stepped"][0] == 0.0
    assert set(ev.metrics) == set(problem.metric_names)


def test_old_fitness_name_is_the_paper_fitness(problem):
    """``fitness = "seed"`` (run folders from before issue 32) is the old name of "paper"."""
    old = HumanoidStepProblem(dataclasses.replace(problem.cfg, fitness="seed"))
    g = _still(problem)
    assert old.evaluate(g).fitness.tolist() == problem.evaluate(g).fitness.tolist()


def test_folding_the_legs_falls_early(problem):
    g = _still(problem)
    s = problem.genome.slices
    for name in ("RHipPitch", "LHipPitch"):
        g[0, s[name]] = problem.genome.lower[s[name]]  # hips flexed to the limit: pitch over
    ev = problem.evaluate(g)
    assert ev.metrics["fell"][0] == 1.0
    assert ev.metrics["time_to_fall_s"][0] < 1.0
    assert ev.fitness[0] < 1.0 + 10.0 * problem.cfg.forward_cap_m


def test_batch_equals_one_by_one(problem):
    rng = np.random.default_rng(3)
    q = _still(problem, 3)
    g = np.clip(q + rng.normal(0, 0.08, q.shape), problem.genome.lower, problem.genome.upper)
    ev = problem.evaluate(g)
    for i in range(3):
        one = problem.evaluate(g[i:i + 1])
        assert one.fitness[0] == ev.fitness[i]
        for k in problem.metric_names:
            assert one.metrics[k][0] == ev.metrics[k][i]


def test_controls_hold_other_servos_and_pin_ends(problem):
    rng = np.random.default_rng(4)
    g = problem.genome.sample(rng, 2)
    ctrl = problem.controls(g)
    assert ctrl.shape == (2, problem.nstep, 22)
    other = np.setdiff1d(np.arange(22), problem.leg_columns)
    np.testing.assert_array_equal(ctrl[:, :, other], np.broadcast_to(
        problem.base[other], (2, problem.nstep, other.size)))
    np.testing.assert_allclose(ctrl[:, 0], np.broadcast_to(problem.base, (2, 22)))
    np.testing.assert_allclose(ctrl[:, -1], np.broadcast_to(problem.base, (2, 22)))


@pytest.mark.parametrize("field,value", [("intervals", 1), ("motion_s", 0.0),
                                         ("bounds_scale", 1.5), ("threads", -1)])
def test_bad_settings_are_one_line_input_errors(field, value):
    from evomotion.errors import InputError

    with pytest.raises(InputError, match=f"problem.{field}"):
        HumanoidStepProblem(HumanoidStepConfig(**{field: value}))


def test_step_fitness_ranks_every_survivor_above_every_fall(step_problem):
    rng = np.random.default_rng(5)
    q = _still(step_problem, 24)
    g = np.clip(q + rng.normal(0, 0.25, q.shape), step_problem.genome.lower,
                step_problem.genome.upper)
    ev = step_problem.evaluate(np.concatenate([_still(step_problem), g]))
    fell = ev.metrics["fell"] == 1.0
    assert fell.any() and (~fell).any()
    total = step_problem.nstep * step_problem.dt
    assert ev.fitness[fell].max() <= total < ev.fitness[~fell].min()
    # standing still: no flight, no turn, no drift -> total + 1 + forward (about 0)
    m = {k: v[0] for k, v in ev.metrics.items()}
    assert m["flight_s"] == 0.0
    c = step_problem.cfg
    quality = m["forward_m"] - c.heading_weight * abs(m["heading_change_rad"]) \
        - c.lateral_weight * abs(m["lateral_m"])
    assert ev.fitness[0] == pytest.approx(total + 1.0 + quality)


def test_flight_counts_gaps_of_at_least_three_steps():
    from evomotion.studies.humanoid_step.problem import flight_steps

    a = np.array([[0, 1, 1, 1, 0, 1, 0, 1, 1, 1, 1], [1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 1],
                  [0] * 11], bool)
    assert flight_steps(a, 3).tolist() == [7, 0, 0]


def test_perturbed_worlds_are_deterministic_and_aggregate():
    cfg = HumanoidStepConfig(intervals=4, motion_s=0.6, hold_s=0.4, threads=2, worlds=3,
                             world_seed=4)
    p1, p2 = HumanoidStepProblem(cfg), HumanoidStepProblem(cfg)
    g = _still(p1, 2)
    e1, e2 = p1.evaluate(g), p2.evaluate(g)
    np.testing.assert_array_equal(e1.fitness, e2.fitness)
    assert np.all((e1.metrics["fall_rate"] >= 0) & (e1.metrics["fall_rate"] <= 1))
    q = HumanoidStepProblem(HumanoidStepConfig(**{**cfg.__dict__, "world_aggregate": "quantile",
                                                  "world_quantile": 0.0}))
    assert np.all(q.evaluate(g).fitness <= e1.fitness + 1e-12)  # the minimum <= the mean


def test_worlds_come_from_the_run_seed_unless_given():
    from evomotion.run.config import resolve_config
    from evomotion.studies import get_study

    s = get_study("humanoid-step")
    cfg = resolve_config(s, None, ["run.seed=7", "problem.worlds=3"])
    assert cfg.problem.world_seed == -1
    assert cfg.problem.with_run_seed(7).world_seed == 7
    fixed = resolve_config(s, None, ["run.seed=7", "problem.worlds=3", "problem.world_seed=2"])
    assert fixed.problem.with_run_seed(7).world_seed == 2
