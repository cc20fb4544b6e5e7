"""humanoid-balance with the structured policy (a phase tape plus feedback): a tiny run, its
exported policy, and the one-line errors when the phase observation is missing (balance and
gym)."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.core.policies import StructuredSpec
from evomotion.core.policies.export import read_policy_npz
from evomotion.errors import InputError
from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.studies import get_study
from evomotion.studies.gym.problem import GymConfig
from evomotion.studies.humanoid_balance.problem import (
    HumanoidBalanceConfig,
    HumanoidBalanceProblem,
)

OBS = "joint_pos,gyro,gravity,phase"
# validate_every 0: the export is the best scored centre, one that two generations moved (the
# default's validation every 10th generation would export generation 0's zero centre)
TINY = ("problem.policy=structured", f"problem.observations={OBS}", "problem.harmonics=1",
        "problem.phase_period_s=0.5", "problem.duration_s=0.3", "problem.eval_episodes=1",
        "problem.episodes=1", "problem.validate_every=0", "problem.threads=1",
        "algorithm.pop_size=4", "algorithm.top_directions=0", "run.generations=2",
        "run.videos=false", "run.seed=3")


def test_a_tiny_structured_run_exports_its_tape_and_gains(tmp_path) -> None:
    s = get_study("humanoid-balance")
    run_study(s, resolve_config(s, None, list(TINY)), tmp_path / "run", quiet=True)
    got = read_policy_npz(tmp_path / "run" / "policy.npz")
    assert isinstance(got.spec, StructuredSpec) and got.spec.harmonics == 1
    p = HumanoidBalanceProblem(HumanoidBalanceConfig(
        policy="structured", observations=OBS, harmonics=1, phase_period_s=0.5,
        duration_s=0.3, threads=1))
    names = list(p.obs_names)
    assert names[-2:] == ["phase:sin", "phase:cos"]
    assert got.spec.phase_columns == (len(names) - 2, len(names) - 1)
    assert got.spec.obs_dim == p.obs_dim and got.spec.act_dim == p.act_dim
    assert got.params.shape == (p.act_dim * 3 + p.act_dim * (p.obs_dim - 2),)
    assert got.params.any()  # two generations moved the centre


def test_the_clock_reaches_the_policy_raw() -> None:
    """A pure tape y = sin(phi) (no feedback) on the NAO: the policy's first action is the
    offset at t = 0 plus the scaled sin of the clock, whatever the normaliser says."""
    p = HumanoidBalanceProblem(HumanoidBalanceConfig(
        policy="structured", observations="joint_pos,phase", harmonics=1, phase_period_s=0.2,
        duration_s=0.1, threads=1, perturb=False, action_scale=0.01))
    a = p.act_dim
    tape = np.zeros((a, 3))
    tape[:, 1] = 1.0
    params = p.policy.params_from_tape(tape)[None]
    o = p.obs_dim
    seen = []
    original = p.policy.act

    def spy(params_, obs, mean, std):
        seen.append(obs[0, -2:].copy())
        return original(params_, obs, mean, std)

    object.__setattr__(p.policy, "act", spy)
    ep = p.play(params, np.full((1, o), 5.0), np.full((1, o), 9.0), np.array([1]))
    k = p.control_steps
    assert len(seen) == int(np.ceil(p.nstep / k))
    t = np.arange(len(seen)) * k * p.dt
    np.testing.assert_allclose(np.array(seen), np.stack(
        [np.sin(2 * np.pi * t / 0.2), np.cos(2 * np.pi * t / 0.2)], -1), atol=1e-9)
    # every joint got 0.01 sin(phi) (offsets from the nominal pose): mean square over steps
    assert ep.action_sq[0] == pytest.approx(np.mean((0.01 * np.sin(2 * np.pi * t / 0.2)) ** 2))


@pytest.mark.parametrize("kw", [{"observations": "joint_pos,gyro"}, {}])
def test_structured_without_phase_is_one_line(kw) -> None:
    with pytest.raises(InputError) as e:
        HumanoidBalanceConfig(policy="structured", **kw).validate()
    assert "needs the phase observation" in str(e.value) and "\n" not in str(e.value)


def test_gym_refuses_the_structured_policy_in_one_line() -> None:
    with pytest.raises(InputError) as e:
        GymConfig(policy="structured").validate()
    assert "Gymnasium tasks lack" in str(e.value) and "\n" not in str(e.value)
