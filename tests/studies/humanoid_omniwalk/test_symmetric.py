"""``problem.symmetric``: the NAO's walk controller searched as a mirror-symmetric policy. On
the controller's real observation and joints, every searched vector is a controller that acts
as its own mirror image (half a gait cycle later); a run exports full controllers; a robot
without a mirror is refused in one line."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.core.policies.export import read_policy_npz
from evomotion.core.policies.mirror import SignedPermutation, with_mirror_image
from evomotion.errors import InputError
from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.sim.robots.nao.mirror import joint_mirror
from evomotion.studies import get_study
from evomotion.studies.humanoid_omniwalk.problem import OmniWalkConfig, OmniWalkProblem

TINY = ("problem.duration_s=1.0", "problem.eval_episodes=1", "problem.episodes=1",
        "problem.threads=1", "algorithm.pop_size=4", "algorithm.top_directions=0",
        "run.generations=2", "run.videos=false", "run.seed=3", "problem.symmetric=true")


@pytest.fixture(scope="module")
def problem() -> OmniWalkProblem:
    return OmniWalkProblem(OmniWalkConfig(duration_s=1.0, threads=1, symmetric=True,
                                          command_feedback=True, command_feedback_start=0.1))


def _action_mirror(problem: OmniWalkProblem) -> SignedPermutation:
    names = list(problem.ctl.driven)
    pairs = [joint_mirror(j) for j in names]
    follow = problem.ctl.followers
    return SignedPermutation([names.index(follow.get(p, p)) for p, _ in pairs],
                             [s for _, s in pairs])


def test_searched_vectors_are_controllers_that_act_as_their_own_mirror_image(problem):
    """Left and right leg swapped, rolls negated, the IMU's y and the gyro's x and z negated,
    the feet's contacts swapped, the command's vy and ω negated, half a cycle later: the
    targets are the mirror image of the targets, for any searched vector (about half the
    controller's numbers)."""
    basis, mirror = problem.mirror.basis, problem.mirror.observation
    assert problem.genome.dim == basis.dim and basis.dim < 0.55 * problem.policy.n_params
    names = list(problem.obs_names)
    # the NAO's conventions, written out (not derived from the code under test): a column's
    # mirror image and its sign
    expected = {"foot_contact:left": ("foot_contact:right", 1),
                "joint_pos:LHipRoll": ("joint_pos:RHipRoll", -1),
                "joint_pos:RAnkleRoll": ("joint_pos:LAnkleRoll", -1),
                "joint_pos:LKneePitch": ("joint_pos:RKneePitch", 1),
                "joint_vel:RHipPitch": ("joint_vel:LHipPitch", 1),
                "joint_vel:LAnkleRoll": ("joint_vel:RAnkleRoll", -1),
                "gravity:x": ("gravity:x", 1), "gravity:y": ("gravity:y", -1),
                "gyro:x": ("gyro:x", -1), "gyro:y": ("gyro:y", 1), "gyro:z": ("gyro:z", -1),
                "command:0": ("command:0", 1), "command:1": ("command:1", -1),
                "command:2": ("command:2", -1)}
    for name, (other, sign) in expected.items():
        i = names.index(name)
        assert (names[int(mirror.perm[i])], mirror.sign[i]) == (other, sign), name
    # the driven joints' mirror, read off the basis: the tape's constant of a joint and of its
    # image are one free number (with the sign), the hip yaw-pitch motor is its own image
    C = problem.policy.unflatten(np.arange(problem.policy.n_params, dtype=float))[0][0]
    C = C.astype(int)
    driven = list(problem.ctl.driven)
    for a, b, sign in (("LHipRoll", "RHipRoll", -1), ("LKneePitch", "RKneePitch", 1),
                       ("LShoulderPitch", "RShoulderPitch", 1),
                       ("LShoulderRoll", "RShoulderRoll", -1),
                       ("LHipYawPitch", "LHipYawPitch", 1)):
        i, j = C[driven.index(a), 0], C[driven.index(b), 0]
        assert basis.index[i] == basis.index[j] >= 0
        assert basis.sign[i] * basis.sign[j] == sign, (a, b)
    rng = np.random.default_rng(0)
    params = np.tile(basis.expand(0.05 * rng.normal(size=basis.dim)), (6, 1))
    o = problem.obs_dim
    count, mean, m2 = with_mirror_image(np.array([9.0]), rng.normal(size=(1, o)),
                                        rng.uniform(1, 2, (1, o)), mirror)
    std = np.sqrt(m2[0] / count[0])
    obs = mean[0] + 0.3 * rng.normal(size=(6, o))
    phi = rng.uniform(0, 2 * np.pi, 6)
    i, j = problem.policy.phase_columns
    obs[:, i], obs[:, j] = np.sin(phi), np.cos(phi)
    mirrored = mirror.apply(obs)
    mirrored[:, i], mirrored[:, j] = np.sin(phi + np.pi), np.cos(phi + np.pi)
    policy, action = problem.policy, _action_mirror(problem)
    # before the joint ranges' clip (the NAO's left and right ranges differ by 0.01 rad)
    wide = type(policy)(**{**{f: getattr(policy, f) for f in
                              ("obs_dim", "act_dim", "phase_columns", "harmonics",
                               "command_columns", "command_feedback", "clip_obs", "offset",
                               "scale")},
                           "low": np.full(policy.act_dim, -10.0),
                           "high": np.full(policy.act_dim, 10.0)})
    y = wide.act(params, obs, mean[0], std) - policy.offset
    np.testing.assert_allclose(wide.act(params, mirrored, mean[0], std) - policy.offset,
                               action.apply(y), atol=1e-12)


def test_the_search_starts_at_the_symmetric_tape_nearest_the_engine(problem):
    x = problem.ctl.initial_params()
    start = problem.policy_params(problem.initial_population(1, np.random.default_rng(0))[0])
    assert np.abs(start - x).max() < 0.02  # the engine is nearly symmetric already


def test_a_symmetric_run_exports_the_full_controller(tmp_path):
    """(Its resume, bit for bit, is the study conformance test's: the NAO's default is
    symmetric.)"""
    s = get_study("humanoid-walk")
    cfg = resolve_config(s, None, list(TINY))
    res = run_study(s, cfg, tmp_path / "run", quiet=True)
    assert res.exit_code == 0
    pol = read_policy_npz(tmp_path / "run" / "policy.npz")
    problem = OmniWalkProblem(cfg.problem)
    assert pol.params.size == problem.policy.n_params
    np.testing.assert_array_equal(pol.params, problem.policy_params(problem.mirror.basis.reduce(
        pol.params)))  # a symmetric controller


def test_a_robot_without_a_mirror_is_one_line():
    with pytest.raises(InputError, match="problem.symmetric: robot 'op3'"):
        OmniWalkProblem(OmniWalkConfig(duration_s=1.0, threads=1, symmetric=True, robot="op3"))
