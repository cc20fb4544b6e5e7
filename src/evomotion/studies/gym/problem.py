"""Any Gymnasium environment as a policy-search problem (``evomotion run gym``).

The genome is a policy's flat parameters (:mod:`evomotion.core.policies`: linear as in ARS, or a
tanh MLP); an evaluation row also carries the observation normaliser and its episodes' seeds
(:mod:`evomotion.studies.policy_search`). The fitness is Gymnasium's own return minus ARS's
survival shift (Mania et al. 2018, section 4: the per-step alive bonus subtracted while training
only; 1 for Hopper, Walker2d and Ant, 5 for Humanoid, 0 otherwise, as their public code); the
metric ``return`` is the plain return, which is what ``stats.csv``'s ``centre_return`` and the
thresholds compare. ``problem.clip_actions = false`` (default) hands the policy's raw action to
the environment, as ARS's public code does with Gym: MuJoCo clamps the controls to the
actuators' ``ctrlrange`` and the control cost sees the raw action, which keeps a linear policy
out of saturation, where a perturbation changes nothing; ``true`` clips the action to the action
space first (the policy, and the exported policy, clip alike).

``problem.backend``: ``"batched"`` steps the v5 Hopper, Walker2d, HalfCheetah and Swimmer
without Gymnasium, bit-identical to it (:mod:`.envs`); ``"gymnasium"`` runs any environment
through ``gymnasium.make``; ``"auto"`` (default) picks the first where it applies.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from evomotion.core.checks import check_choice, check_fields, check_number, check_text
from evomotion.core.problem import Evaluation, GenomeSpec, Sense
from evomotion.errors import InputError
from evomotion.studies.gym.envs import BatchedTask, task_of
from evomotion.studies.gym.episodes import Episodes, run_batched, run_gymnasium
from evomotion.studies.policy_search import EpisodeRows, neutral_rows, split_rows
from evomotion.studies.policy_validation import check_validation

BACKENDS = ("auto", "batched", "gymnasium")
#: ARS's survival shift per task (their public code), subtracted per step while training
ARS_SHIFT = {"Hopper": 1.0, "Walker2d": 1.0, "Ant": 1.0, "Humanoid": 5.0}
MAX_EPISODES = 1000


@dataclass(frozen=True)
class GymConfig:
    """``[problem]`` of the gym study."""

    env: str = "Hopper-v5"  # a Gymnasium id (its MuJoCo extra installed: gymnasium[mujoco])
    policy: str = "linear"  # "linear" (ARS) or "mlp" (tanh hidden layers)
    hidden: int = 32  # MLP: units per hidden layer
    layers: int = 2  # MLP: hidden layers
    normalize: bool = True  # ARS V2 observation normalisation (false: V1)
    #: start the search from this exported policy (a policy.npz or a run folder holding one,
    #: of the same controller; "" the study's own start): studies/policy_start.py
    start_policy: str = ""
    #: validate the centre of every this many generations on validate_episodes fixed episodes
    #: and export the best validated one (0: export the best single evaluation; the
    #: winner's curse): studies/policy_validation.py
    validate_every: int = 0
    validate_episodes: int = 32
    episodes: int = 1  # training episodes per individual and generation
    eval_episodes: int = 5  # episodes of the centre per generation (the reported return)
    reward_shift: float = -1.0  # per-step shift while training; < 0: ARS's for the task
    max_episode_steps: int = 0  # 0: the environment's own limit (1000 for MuJoCo v5)
    backend: str = "auto"
    param_bound: float = 100.0  # the genome box +- this (the ES starts at its middle, 0)
    clip_actions: bool = False  # clip to the action space before the env (false: ARS's code)

    def validate(self) -> None:
        check_fields(self, "problem")
        check_text("problem.env", self.env)
        check_text("problem.start_policy", self.start_policy)
        check_validation(self.validate_every, self.validate_episodes)
        if self.policy == "structured":
            raise InputError("problem.policy: the structured policy needs a phase observation "
                             "(sin/cos of a gait clock), which Gymnasium tasks lack; use linear "
                             "or mlp")
        check_choice("problem.policy", self.policy, ("linear", "mlp"))
        check_choice("problem.backend", self.backend, BACKENDS)
        check_number("problem.hidden", self.hidden, lo=1, hi=4096, integer=True)
        check_number("problem.layers", self.layers, lo=1, hi=8, integer=True)
        for key in ("episodes", "eval_episodes"):
            check_number(f"problem.{key}", getattr(self, key), lo=1, hi=MAX_EPISODES,
                         integer=True)
        check_number("problem.reward_shift", self.reward_shift, lo=-1.0, hi=1e6)
        check_number("problem.max_episode_steps", self.max_episode_steps, lo=0, hi=10**7,
                     integer=True)
        check_number("problem.param_bound", self.param_bound, lo=1e-6, hi=1e6)
        for key in ("normalize", "clip_actions"):
            if not isinstance(getattr(self, key), bool):
                raise InputError(f"problem.{key}: expected true or false, got "
                                 f"{getattr(self, key)!r}")


def make_env(env_id: str) -> Any:
    """``gymnasium.make(env_id)`` with one-line errors (not installed, unknown id)."""
    try:
        import gymnasium
    except ImportError:
        raise InputError("problem.env: the gym study needs Gymnasium: pip install "
                         "'evomotion[gym]'") from None
    import mujoco

    # MuJoCo's compiler warns about some of Gymnasium's assets (Swimmer's deprecated
    # settotalmass) on stderr and in a MUJOCO_LOG.TXT in the working folder: nothing may be
    # written outside the run folder, so warnings while making the environment are dropped
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda message: None)
    try:
        return gymnasium.make(env_id)
    except Exception as e:  # noqa: BLE001 - gymnasium raises many kinds for a bad id
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise InputError(f"problem.env: cannot make {env_id!r}: {first}") from None
    finally:
        mujoco.set_mju_user_warning(previous)


class GymProblem:
    """Rows of policy parameters (+ normaliser and seeds) -> Gymnasium returns."""

    sense: Sense = "max"
    metric_names: tuple[str, ...] = ("return", "steps")

    def __init__(self, cfg: GymConfig) -> None:
        from evomotion.core.policies import make_policy

        cfg.validate()
        self.cfg = cfg
        env = make_env(cfg.env)
        space_o, space_a = env.observation_space, env.action_space
        if len(getattr(space_o, "shape", ()) or ()) != 1 or \
                len(getattr(space_a, "shape", ()) or ()) != 1:
            raise InputError(f"problem.env: {cfg.env} needs a flat Box observation and action "
                             "space")
        self.obs_dim, self.act_dim = int(space_o.shape[0]), int(space_a.shape[0])
        # the policy's (and the episodes') action bounds: the action space, or none
        unbounded = np.full(self.act_dim, np.inf)
        self.low = np.asarray(space_a.low, float) if cfg.clip_actions else -unbounded
        self.high = np.asarray(space_a.high, float) if cfg.clip_actions else unbounded
        options = {"hidden": (cfg.hidden,) * cfg.layers} if cfg.policy == "mlp" else {}
        self.policy = make_policy(cfg.policy, self.obs_dim, self.act_dim, low=self.low,
                                  high=self.high, **options)
        lo, hi = self.policy.genome_bounds(cfg.param_bound)
        self.genome = GenomeSpec(lo, hi)
        name = cfg.env.partition("-")[0]
        self.shift = ARS_SHIFT.get(name, 0.0) if cfg.reward_shift < 0 else cfg.reward_shift
        limit = getattr(getattr(env, "spec", None), "max_episode_steps", None) or 1000
        self.max_steps = cfg.max_episode_steps or int(limit)
        task = task_of(cfg.env)
        if cfg.backend == "batched" and task is None:
            raise InputError(f"problem.backend: 'batched' steps only the v5 Hopper, Walker2d, "
                             f"HalfCheetah and Swimmer; {cfg.env} needs 'gymnasium' or 'auto'")
        self.backend = "gymnasium" if cfg.backend == "gymnasium" or task is None else "batched"
        self.task = (BatchedTask.from_env(env, task) if self.backend == "batched" and task
                     else None)
        self._env0 = env
        self.episodes, self.eval_episodes = cfg.episodes, cfg.eval_episodes
        self.normalize = cfg.normalize
        self._envs: list[Any] = []
        self._datas: list[Any] = []

    def _run(self, policy, owner: np.ndarray, seeds: np.ndarray) -> Episodes:
        n = len(seeds)
        if self.task is not None:
            import mujoco

            while len(self._datas) < n:
                self._datas.append(mujoco.MjData(self.task.model))
            return run_batched(self.task, policy, owner, seeds, self.max_steps, self.low,
                               self.high, self._datas)
        while len(self._envs) < n:
            self._envs.append(self._env0 if not self._envs else make_env(self.cfg.env))
        return run_gymnasium(self._envs, policy, owner, seeds, self.max_steps, self.low,
                             self.high)

    def physics_record(self) -> dict[str, Any]:
        """``physics.json``: the environment, how it is stepped, the MuJoCo and Gymnasium
        versions and the host facts a CPU run's bits depend on
        (:func:`~evomotion.sim.cpu_platform.cpu_platform`); a resume where they differ is
        noted in the log (:mod:`evomotion.studies.run_hooks`)."""
        import gymnasium
        import mujoco

        from evomotion.sim.cpu_platform import cpu_platform

        return {"backend": "cpu", "precision": "float64", "mujoco": mujoco.__version__,
                "gymnasium": gymnasium.__version__, "env": self.cfg.env,
                "env_backend": self.backend,
                "guarantee": "bit-identical for one seed, whatever the evaluator, on machines "
                             "with the same mujoco, gymnasium, numpy, numpy_simd and blas "
                             "(sim/cpu_platform.py)",
                **cpu_platform()}

    def evaluation_rows(self, genomes: np.ndarray) -> np.ndarray:
        """``genomes`` as rows with no normalisation and the episodes from seed 0."""
        return neutral_rows(genomes, self.obs_dim, self.episodes)

    def evaluate(self, rows: np.ndarray) -> Evaluation:
        params, mean, std, seeds, episodes = split_rows(np.asarray(rows, float),
                                                        self.genome.dim, self.obs_dim)
        eps = EpisodeRows.of(seeds, episodes, MAX_EPISODES)
        spec = self.policy

        def policy(rows_: np.ndarray, obs: np.ndarray) -> np.ndarray:
            # one normaliser per generation: the rows of a batch share it (grouped if not)
            out = np.empty((len(rows_), self.act_dim))
            keys = np.concatenate([mean[rows_], std[rows_]], axis=1)
            uniq, inv = np.unique(keys, axis=0, return_inverse=True)
            for g in range(len(uniq)):
                sel = inv.ravel() == g
                out[sel] = spec.act(params[rows_[sel]], obs[sel], uniq[g, :self.obs_dim],
                                    uniq[g, self.obs_dim:])
            return out

        ep = self._run(policy, eps.owner, eps.seeds)
        ret, steps = eps.mean(ep.returns), eps.mean(ep.steps)
        fitness = ret - self.shift * steps
        return Evaluation(fitness, {"return": ret, "steps": steps,
                                    **eps.moments(ep.obs_count, ep.obs_mean, ep.obs_m2)})
