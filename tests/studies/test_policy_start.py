"""A policy search started from an exported policy (``problem.start_policy``,
studies/policy_start.py): the first centre is the file's policy acting as exported, a resume of
such a run is bit-identical, and every file that does not fit is one line."""

from __future__ import annotations

import shutil
import subprocess
import sys

import numpy as np
import pytest

from evomotion.core.policies.export import read_policy_npz, write_policy_npz
from evomotion.core.policies.normalizer import mean_std
from evomotion.errors import InputError
from evomotion.studies.policy_search import make_policy_driver, normaliser, policy_rows
from evomotion.studies.policy_start import START_OBS_COUNT, start_point

gym = pytest.importorskip("gymnasium")

from evomotion.run.config import resolve_config  # noqa: E402
from evomotion.run.runner import run_study  # noqa: E402
from evomotion.studies.gym.problem import GymConfig, GymProblem  # noqa: E402
from evomotion.studies.gym.study import STUDY as GYM  # noqa: E402

SETS = ("problem.max_episode_steps=40", "problem.eval_episodes=2", "run.evaluator=serial")


def _cfg(*sets: str):
    return resolve_config(GYM, None, [*SETS, *sets])


@pytest.fixture(scope="module")
def source(tmp_path_factory):
    """A short ARS run whose exported policy carries a normaliser that is not the identity."""
    out = tmp_path_factory.mktemp("src") / "run"
    run_study(GYM, _cfg("algorithm.name=ars", "algorithm.pop_size=4", "algorithm.top_directions=0",
                   "run.generations=3"),
              out, quiet=True)
    got = read_policy_npz(out / "policy.npz")
    rng = np.random.default_rng(1)
    o = got.obs_mean.size
    # whatever generation's centre was exported: non-zero numbers and a non-trivial normaliser
    write_policy_npz(out / "policy.npz", got.spec,
                     got.params + rng.normal(scale=0.01, size=got.params.size),
                     got.obs_mean + rng.normal(size=o), got.obs_std * rng.uniform(0.5, 2, o))
    return out


@pytest.mark.parametrize("algo", ["ars", "openai_es", "pgpe", "snes", "cmaes"])
def test_the_first_centre_is_the_file_acting_as_exported(source, algo):
    cfg = _cfg(f"algorithm.name={algo}", f"problem.start_policy='{source}'")
    problem = GymProblem(cfg.problem)
    driver = make_policy_driver(problem, cfg)
    state = driver.init(np.random.default_rng(0))
    got = read_policy_npz(source / "policy.npz")
    # the distribution's mean (CMA-ES deploys the best point seen, none yet: its mean)
    centre = driver.opt.to_genome(state.opt.mean) if algo == "cmaes" else \
        driver.opt.center(state.opt)
    np.testing.assert_allclose(np.asarray(centre), got.params, rtol=0, atol=1e-12)  # box units
    assert int(state.obs.count) == START_OBS_COUNT
    mean, std = normaliser(state.obs, True)
    np.testing.assert_array_equal(mean, got.obs_mean)
    np.testing.assert_array_equal(std, got.obs_std)  # exactly: START_OBS_COUNT = 2^20 + 1
    # the centre scores what the file scores with its own normaliser
    a = problem.evaluate(policy_rows(got.params[None], mean, std, 7, 1)).metrics["return"][0]
    b = problem.evaluate(policy_rows(got.params[None], got.obs_mean, got.obs_std, 7, 1)
                         ).metrics["return"][0]
    assert a == pytest.approx(b, abs=1e-9)


def test_a_started_run_resumes_bit_for_bit(source, tmp_path):
    sets = ("algorithm.name=ars", "algorithm.pop_size=4", "algorithm.top_directions=0",
            f"problem.start_policy='{source}'")
    whole, split = tmp_path / "whole", tmp_path / "split"
    run_study(GYM, _cfg(*sets, "run.generations=3"), whole, quiet=True)
    run_study(GYM, _cfg(*sets, "run.generations=1"), split, quiet=True)
    run_study(GYM, _cfg(*sets, "run.generations=3"), split, quiet=True, resume=True)
    assert (whole / "policy.npz").read_bytes() == (split / "policy.npz").read_bytes()
    # a resume does not read the start again: its checkpoint holds everything
    again, src = tmp_path / "again", tmp_path / "src"
    shutil.copytree(source, src)
    sets2 = (*sets[:3], f"problem.start_policy='{src}'")
    run_study(GYM, _cfg(*sets2, "run.generations=1"), again, quiet=True)
    shutil.rmtree(src)
    run_study(GYM, _cfg(*sets2, "run.generations=3"), again, quiet=True, resume=True)
    assert (again / "policy.npz").read_bytes() == (whole / "policy.npz").read_bytes()
    strip = [line.split(",")[:9] for line in (whole / "stats.csv").read_text().splitlines()]
    assert strip == [line.split(",")[:9] for line in (split / "stats.csv").read_text().splitlines()]


def _problem(**kw):
    return GymProblem(GymConfig(max_episode_steps=40, **kw))


@pytest.mark.parametrize("kw, where", [
    ({"env": "Walker2d-v5"}, "maps 11 observations to 3 actions"),
    ({"policy": "mlp"}, "is a linear policy, this run's is mlp"),
    ({"param_bound": 1e-6}, "outside this run's box"),
    ({"normalize": False}, "expected problem.normalize=true"),
])
def test_a_policy_that_does_not_fit_is_one_line(source, kw, where):
    with pytest.raises(InputError, match="problem.start_policy") as e:
        start_point(_problem(**kw), str(source))
    assert where in str(e.value) and "\n" not in str(e.value)


def test_another_action_range_is_named(source, tmp_path):
    got = read_policy_npz(source / "policy.npz")
    spec = type(got.spec)(obs_dim=got.spec.obs_dim, act_dim=got.spec.act_dim,
                          scale=got.spec.scale * 2, offset=got.spec.offset, low=got.spec.low,
                          high=got.spec.high, clip_obs=got.spec.clip_obs)
    f = write_policy_npz(tmp_path / "policy.npz", spec, got.params, got.obs_mean, got.obs_std)
    with pytest.raises(InputError, match="'action_scale' differs"):
        start_point(_problem(), str(f))


def test_without_normalisation_an_identity_file_starts_with_no_states_seen(source, tmp_path):
    got = read_policy_npz(source / "policy.npz")
    o = got.obs_mean.size
    f = write_policy_npz(tmp_path / "policy.npz", got.spec, got.params, np.zeros(o), np.ones(o))
    start = start_point(_problem(normalize=False), str(f))
    assert int(start.obs.count) == 0
    np.testing.assert_array_equal(start.genome, got.params)


def test_missing_files_are_one_line(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        start_point(_problem(), str(tmp_path / "nowhere"))
    with pytest.raises(InputError, match="no policy.npz in it"):
        start_point(_problem(), str(tmp_path))
    assert start_point(_problem(), "") is None
    with pytest.raises(InputError, match="expected a readable path"):
        start_point(_problem(), "~no-such-user-of-this-machine/policy.npz")


def test_a_symmetric_walk_starts_from_its_free_numbers_and_refuses_an_asymmetric_one(tmp_path):
    from evomotion.studies.humanoid_omniwalk.problem import OmniWalkConfig, OmniWalkProblem

    p = OmniWalkProblem(OmniWalkConfig(symmetric=True, command_feedback=True, threads=1))
    z = p.initial_population(1, np.random.default_rng(0))[0]
    z = z + np.random.default_rng(1).normal(scale=1e-3, size=z.size)
    mean, std = np.zeros(p.obs_dim), np.ones(p.obs_dim)
    f = write_policy_npz(tmp_path / "sym.npz", p.policy, p.policy_params(z), mean, std)
    got = start_point(p, str(f))
    np.testing.assert_allclose(got.genome, z, rtol=0, atol=1e-12)
    x = p.policy_params(z) + np.random.default_rng(2).normal(scale=1e-3, size=p.policy.n_params)
    f = write_policy_npz(tmp_path / "asym.npz", p.policy, x, mean, std)
    with pytest.raises(InputError, match="not a mirror-symmetric controller"):
        start_point(p, str(f))
    m, sd = mean_std(got.obs)  # the identity normaliser, weighted
    np.testing.assert_array_equal(m, 0.0)
    np.testing.assert_array_equal(sd, 1.0)


def test_the_cli_refuses_a_bad_start_in_one_line_before_making_the_folder(tmp_path):
    out = tmp_path / "run"
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "gym", "--out", str(out),
                        "--set", f"problem.start_policy='{tmp_path / 'nowhere.npz'}'"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode != 0 and "Traceback" not in r.stderr
    assert r.stderr.strip().count("\n") == 0 and "problem.start_policy" in r.stderr
    assert not out.exists()
