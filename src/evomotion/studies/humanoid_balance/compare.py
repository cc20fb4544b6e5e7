"""A humanoid-balance run's policy measured on unseen pushed worlds, beside standing still.

``evomotion humanoid-balance compare RUN --worlds 100 [--push 4]``: the best centre
(``policy.npz`` of the run folder, its frozen normaliser inside) and the open-loop stand-still
(the zero policy: the nominal pose held) are played in the **same** ``worlds`` episodes of the
run's task (:mod:`.episodes`), drawn from seeds no training episode uses
(:data:`EVAL_SEED_BASE` + ``seed * worlds`` ...); ``--push P`` sets every push to ``P`` N s on
the NAO (scaled by mass for another robot; direction and time drawn as in training). Reported:
survival (share of worlds never fallen), mean time up (s), mean tilt.

:func:`replay_command` is ``evomotion replay RUN`` for such a run (``--stress N``: survival in
N worlds; ``--video``: one world rendered).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.errors import InputError
from evomotion.studies.humanoid_balance.episodes import Episodes, push_range

STUDY_NAME = "humanoid-balance"
#: unseen worlds' seeds start here: above every training seed (< 2^31, policy_search)
EVAL_SEED_BASE = 2**40
MAX_WORLDS = 10_000


def load_run(path: str | Path, option: str = "RUN") -> tuple[Any, Any, Path]:
    """(problem, exported policy, run folder) of a humanoid-balance run folder or the
    ``policy.npz`` inside one; anything else is one :class:`InputError` line."""
    from evomotion.core.policies.export import read_policy_npz
    from evomotion.run.config import config_from_dict, run_of_study
    from evomotion.studies import get_study

    p = Path(path)
    folder = p.parent if p.name == "policy.npz" else p
    folder = run_of_study(folder, STUDY_NAME, option)
    npz = folder / "policy.npz"
    if not npz.is_file():
        raise InputError(f"{option} {path}: no policy.npz yet (the run has not checkpointed "
                         "a policy)")
    from evomotion.run.config import config_from_run_dir

    _, raw = config_from_run_dir(folder)
    cfg = config_from_dict(get_study(STUDY_NAME), raw)
    from evomotion.studies.humanoid_balance.problem import HumanoidBalanceProblem

    problem = HumanoidBalanceProblem(cfg.problem)
    policy = read_policy_npz(npz)
    if policy.spec.obs_dim != problem.obs_dim or policy.spec.act_dim != problem.act_dim or \
            policy.spec.kind != problem.policy.kind:
        raise InputError(f"{npz}: a {policy.spec.kind} policy of {policy.spec.obs_dim} "
                         f"observations and {policy.spec.act_dim} actions; the run's config "
                         f"needs {problem.policy.kind} {problem.obs_dim} -> {problem.act_dim}")
    return problem, policy, folder


def eval_seeds(worlds: int, seed: int) -> np.ndarray:
    return EVAL_SEED_BASE + int(seed) * MAX_WORLDS + np.arange(int(worlds))


def play_policy(problem: Any, policy: Any, seeds: np.ndarray, push_ns: float | None = None,
                zero: bool = False, record_states: bool = False) -> Episodes:
    """The exported ``policy`` (or with ``zero`` the stand-still) in the worlds of ``seeds``."""
    n = len(seeds)
    params = np.zeros((n, policy.params.size)) if zero else np.tile(policy.params, (n, 1))
    mean, std = np.tile(policy.obs_mean, (n, 1)), np.tile(policy.obs_std, (n, 1))
    return problem.play(params, mean, std, seeds, push_ns, record_states)


def summary(ep: Episodes) -> dict[str, float]:
    return {"survival": float(ep.survived.mean()), "time_up_s": float(ep.time_up_s.mean()),
            "tilt_rad": float(ep.tilt_rad.mean()), "score": float(ep.score.mean())}


def check_options(worlds: int, push_ns: float | None, seed: int) -> None:
    from evomotion.core.checks import check_number

    check_number("--worlds", worlds, lo=1, hi=MAX_WORLDS, integer=True)
    check_number("--seed", seed, lo=0, hi=2**20, integer=True)
    if push_ns is not None:
        check_number("--push", push_ns, lo=0.0, hi=1000.0)


def compare(run: str | Path, worlds: int = 100, push_ns: float | None = None,
            seed: int = 0) -> dict[str, Any]:
    """The policy and the stand-still on the same ``worlds`` unseen worlds (module doc)."""
    check_options(worlds, push_ns, seed)
    problem, policy, folder = load_run(run)
    scaled = None if push_ns is None else push_range(problem.robot, push_ns, push_ns)[0]
    seeds = eval_seeds(worlds, seed)
    out = {"run": str(folder), "robot": problem.robot.name, "worlds": int(worlds),
           "seed": int(seed), "duration_s": problem.cfg.duration_s,
           "push_ns": (list(problem.draw.push_ns) if scaled is None else [scaled, scaled]),
           "policy": summary(play_policy(problem, policy, seeds, scaled)),
           "stand_still": summary(play_policy(problem, policy, seeds, scaled, zero=True))}
    problem.sim.close()
    return out


def table(res: dict[str, Any]) -> str:
    lo, hi = res["push_ns"]
    push = f"{lo:g} N s" if lo == hi else f"U({lo:g}, {hi:g}) N s"
    lines = [f"{res['robot']}, {res['worlds']} unseen perturbed worlds, {res['duration_s']:g} s "
             f"each, one push of {push} in a random horizontal direction (seed {res['seed']})",
             "", "| controller | survival | mean time up (s) | mean tilt (deg) |",
             "|---|---|---|---|"]
    for key, name in (("policy", "evolved policy"), ("stand_still", "stand still (open loop)")):
        r = res[key]
        lines.append(f"| {name} | {100 * r['survival']:.0f} % | {r['time_up_s']:.2f} | "
                     f"{np.degrees(r['tilt_rad']):.1f} |")
    return "\n".join(lines)


def compare_command(run: Path, worlds: int = 100, push_ns: float | None = None,
                    seed: int = 0, json_out: bool = False) -> str:
    res = compare(run, worlds, push_ns, seed)
    return json.dumps(res, indent=1) if json_out else table(res)
