"""Study ``gym``: policies for any Gymnasium environment by evolution strategies (ARS, OpenAI-ES,
PGPE, SNES, CMA-ES), through the run loop.

``evomotion run gym --set problem.env=Hopper-v5`` evolves a linear policy (on Hopper-v5, the
default environment, and on Swimmer-v5 with CMA-ES from the zero policy, which reached ARS's
thresholds in 5 of 5 seeds where ARS reached them in 3 and 1: ``docs/gym.md``; on HalfCheetah,
Walker2d, Ant and Humanoid with ARS V2-t and Mania et al. 2018's hyperparameters of the task,
on any other environment with their Hopper setting; ``--preset paper``: the paper's ARS of the
task everywhere, V1-t on Swimmer; another version of these tasks, ``Walker2d-v4``, gets its v5
id's settings) and writes, beside the run's usual files, ``policy.npz``,
``policy.py`` (numpy only) and ``policy.onnx`` of the best centre; ``stats.csv`` has
``centre_return`` (the mean return of the centre on ``problem.eval_episodes`` unseen
episodes), ``train_episodes`` and ``env_steps``. ``run.target`` stops at a return threshold.
"""

from __future__ import annotations

from evomotion.studies.base import Study, lazy_hook
from evomotion.studies.gym.problem import GymConfig, GymProblem
from evomotion.studies.policy_search import POLICY_OPTIMIZERS, policy_algorithms  # noqa: F401 (tests read it here)
from evomotion.studies.view import lazy

#: ARS V2-t on Hopper (Mania et al. 2018; the RL-zoo setting of their code): alpha 0.01,
#: N 8 directions, b 4, nu 0.025; the default where no environment's own applies, and
#: ``--preset paper`` on an environment the paper did not run
PAPER_ARS = {"name": "ars", "pop_size": 16, "step_size": 0.01, "noise_std": 0.025,
             "top_directions": 4}


def _ars(alpha: float, n: int, b: int, nu: float) -> dict:
    """ARS with step size alpha, N directions (2N episodes a generation), the b best, noise nu."""
    return {"name": "ars", "pop_size": 2 * n, "step_size": alpha, "noise_std": nu,
            "top_directions": b}


#: The paper's hyperparameters of each task (Mania et al. 2018, appendix Table 9, as their
#: public code and the RL zoo give them; /shared/reference/policy-search.md): V2-t with the
#: observation normalised, V1-t (not normalised) on Swimmer; the reward shift during training
#: is the task's own (problem.reward_shift < 0)
PAPER_ARS_BY_ENV = {
    "Swimmer-v5": {"algorithm": _ars(0.02, 1, 1, 0.01), "problem": {"normalize": False}},
    "Hopper-v5": {"algorithm": dict(PAPER_ARS)},
    "HalfCheetah-v5": {"algorithm": _ars(0.02, 32, 4, 0.03)},
    "Walker2d-v5": {"algorithm": _ars(0.03, 40, 30, 0.025)},
    "Ant-v5": {"algorithm": _ars(0.015, 60, 20, 0.025)},
    "Humanoid-v5": {"algorithm": _ars(0.02, 230, 230, 0.0075)},
}

#: CMA-ES on Hopper-v5 and Swimmer-v5 (docs/gym.md): from the zero policy (the box's centre),
#: sigma 0.1 (of the +-100 box, problem.param_bound), IPOP restarts; lambda 14 for Hopper's
#: 33 weights, 12 for Swimmer's 16
HOPPER_CMAES = {"name": "cmaes", "sigma0": 0.0005, "x0": "center"}

#: The defaults per environment ("": none given, Hopper-v5): what was measured best there
#: (docs/gym.md): CMA-ES on Hopper and Swimmer, the paper's ARS on the other four tasks
ENV_DEFAULTS = {**{env: {"algorithm": dict(HOPPER_CMAES)}
                   for env in ("", "Hopper-v5", "Swimmer-v5")},
                **{env: {sec: dict(keys) for sec, keys in sections.items()}  # copies
                   for env, sections in PAPER_ARS_BY_ENV.items()
                   if env not in ("Swimmer-v5", "Hopper-v5")}}

def v5_id(env_id: str) -> str:
    """The id whose defaults and preset settings ``env_id`` reads: another version of a task
    listed here (``Walker2d-v4``) reads its v5 id's (the paper's settings and what was measured
    are per task; the reward shift is too: problem.py), any other id itself."""
    name, dash, version = env_id.partition("-")
    v5 = f"{name}-v5"
    known = v5 in PAPER_ARS_BY_ENV and dash and version[:1] == "v" and version[1:].isdigit()
    return v5 if known else env_id


STUDY = Study(
    name="gym",
    description="Policies for Gymnasium environments by ES (ARS, OpenAI-ES, PGPE, SNES, "
                "CMA-ES).",
    problem_config=GymConfig,
    make_problem=GymProblem,
    defaults={"algorithm": dict(PAPER_ARS),
              # episodes in evaluation processes, one per core (mj_step holds the GIL)
              "run": {"generations": 1000, "checkpoint_every": 10, "evaluator": "process"}},
    robot_defaults=ENV_DEFAULTS,
    defaults_key="env",
    defaults_alias=v5_id,
    robot_presets={"paper": PAPER_ARS_BY_ENV},
    algorithm_tunings={"cmaes": dict(HOPPER_CMAES)},  # picked on another env: the same sigma
    presets={"paper": {"algorithm": dict(PAPER_ARS)}},
    preset_notes={"paper": "ARS with the paper's hyperparameters of the task (V2-t, V1-t on "
                           "Swimmer; Hopper's elsewhere)"},
    core_algorithms=(),
    algorithms=policy_algorithms(),
    on_checkpoint=lazy_hook("evomotion.studies.gym.artifacts", "write_policy"),
    finalize=lazy_hook("evomotion.studies.gym.artifacts", "finalize"),
    best_record=lazy_hook("evomotion.studies.gym.artifacts", "best_record"),
    replay=None,
    replay_run=lazy("evomotion.studies.gym.replay", "replay_command"),
    smoke=("problem.env=Hopper-v5", "problem.max_episode_steps=20", "problem.eval_episodes=1",
           "algorithm.pop_size=4", "run.evaluator=serial"),
)
