"""What choosing the export on validation episodes changes (``problem.validate_every``,
docs/policies.md): for each humanoid-walk or humanoid-balance run made with validation, the two
centres its state holds, side by side on the same episodes:

- ``best``: the centre with the best single per-generation score (what the run would have
  exported without validation; the winner's curse);
- ``validated``: the centre with the best mean return on the run's fixed validation episodes
  (what it exports).

For each: its generation, the score that chose it, its mean return on the validation
episodes (the same for both, ``problem.validate_episodes`` of them) and on ``--fresh`` fresh
episodes of the training task (seeds from 2^39, apart from training's, validation's and
compare's; a gym run: this alone), then the measure users read: ``humanoid-walk compare``'s
worlds (survival and tracking errors over ``--worlds`` worlds x ``--duration`` s; the
controller alone) or ``humanoid-balance compare``'s worlds at each ``--push``.

    python benchmarks/validated_export.py RUN [RUN ...] [--worlds 100] [--duration 60]
        [--push 4 3] [--fresh 200] [--json]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

FRESH_SEED_BASE = 2**39


def centres(run: Path) -> tuple[str, object, int, dict]:
    """``(study name, problem, validation episodes, {which: (x, mean, std, generation,
    chosen by)})``."""
    from evomotion.run.checkpoint import candidates, read_checkpoint
    from evomotion.run.config import config_from_dict, config_from_run_dir
    from evomotion.studies import get_study

    name, raw = config_from_run_dir(run)
    study = get_study(name)
    cfg = config_from_dict(study, raw)
    problem = study.make_problem(cfg.problem)
    a, meta = read_checkpoint(run, candidates(run)[0])
    if "state.valid.x" not in a:
        raise SystemExit(f"error: {run}: no validated centre (run with problem.validate_every)")
    best_gen = _best_generation(run)
    return name, problem, int(cfg.problem.validate_episodes), {
        "best": (a["state.best_x"], a["state.best_obs_mean"], a["state.best_obs_std"],
                 best_gen, -float(meta["state.best_cost"])),
        "validated": (a["state.valid.x"], a["state.valid.obs_mean"], a["state.valid.obs_std"],
                      int(meta["state.valid.generation"]), -float(meta["state.valid.cost"]))}


def _best_generation(run: Path) -> int:
    import csv

    with open(run / "stats.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    scores = np.array([float(r["centre_return"]) for r in rows])
    return int(rows[int(np.nanargmax(scores))]["generation"])


def returns(problem, x, mean, std, seeds: np.ndarray) -> np.ndarray:
    from evomotion.studies.policy_search import policy_rows

    rows = policy_rows(np.repeat(np.asarray(x, float)[None], len(seeds), axis=0), mean, std,
                       seeds, 1)
    out = []
    for a in range(0, len(rows), 64):
        out.append(np.asarray(problem.evaluate(rows[a:a + 64]).metrics["return"], float))
    return np.concatenate(out)


def walk_measure(problem, x, mean, std, worlds: int, duration_s: float) -> dict:
    import dataclasses

    from evomotion.studies.humanoid_omniwalk.compare import (
        EVAL_SEED_BASE,
        MAX_WORLDS,
        _play,
        _summary,
    )
    from evomotion.studies.humanoid_omniwalk.problem import OmniWalkProblem

    p = OmniWalkProblem(dataclasses.replace(problem.cfg, duration_s=duration_s))
    params = p.policy_params(x)
    s = _summary(_play(p, params, mean, std, EVAL_SEED_BASE + 0 * MAX_WORLDS
                       + np.arange(worlds)))
    p.sim.close()
    return {k: s[k] for k in ("survival", "relative_speed_error", "steady_relative_speed_error",
                              "relative_yaw_rate_error", "steady_relative_yaw_rate_error")}


def balance_measure(problem, x, mean, std, worlds: int, pushes: list[float]) -> dict:
    from evomotion.core.policies.export import ExportedPolicy
    from evomotion.studies.humanoid_balance.compare import eval_seeds, play_policy

    pol = ExportedPolicy(problem.policy, np.asarray(x, float), mean, std)
    return {f"survival_{p:g}ns": float(play_policy(problem, pol, eval_seeds(worlds, 0), p)
                                       .survived.mean()) for p in pushes}


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("runs", type=Path, nargs="+")
    ap.add_argument("--worlds", type=int, default=100)
    ap.add_argument("--duration", type=float, default=60.0)
    ap.add_argument("--push", type=float, nargs="+", default=[4.0, 3.0])
    ap.add_argument("--fresh", type=int, default=200)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    from evomotion.errors import InputError
    from evomotion.studies.policy_validation import validation_seeds

    results = []
    for run in a.runs:
        t0 = time.perf_counter()
        try:
            name, problem, k, found = centres(run)
        except InputError as e:  # not a run folder, a damaged config or checkpoint: one line
            raise SystemExit(f"error: {e}") from None
        res: dict = {"run": str(run), "study": name, "validate_episodes": k}
        for which, (x, mean, std, gen, score) in found.items():
            val = returns(problem, x, mean, std, validation_seeds(k))
            fresh = returns(problem, x, mean, std, FRESH_SEED_BASE + np.arange(a.fresh))
            r = {"generation": gen, "chosen_by": score, "validation": float(val.mean()),
                 "fresh": float(fresh.mean()),
                 "fresh_se": float(fresh.std(ddof=1) / math.sqrt(len(fresh))),
                 "fresh_returns": fresh}
            if name == "humanoid-walk":
                r.update(walk_measure(problem, x, mean, std, a.worlds, a.duration))
            elif name == "humanoid-balance":
                r.update(balance_measure(problem, x, mean, std, a.worlds, a.push))
            res[which] = r
        d = res["validated"]["fresh_returns"] - res["best"]["fresh_returns"]
        res["fresh_paired_diff"] = float(d.mean())
        res["fresh_paired_se"] = float(d.std(ddof=1) / math.sqrt(len(d)))
        res["seconds"] = round(time.perf_counter() - t0, 1)
        for which in ("best", "validated"):
            del res[which]["fresh_returns"]
        results.append(res)
        if hasattr(problem, "sim"):
            problem.sim.close()
        if not a.json:
            print_run(res)
    if a.json:
        print(json.dumps(results, indent=1))
    return 0


def print_run(res: dict) -> None:
    keys = [k for k in res["best"] if k not in ("generation", "chosen_by", "validation",
                                                  "fresh", "fresh_se")]
    print(f"{res['run']} ({res['study']}, {res['seconds']} s)")
    print("| export | generation | chosen by | validation return "
          f"({res['validate_episodes']} episodes) | fresh return |"
          + "".join(f" {k} |" for k in keys))
    print("|---" * (5 + len(keys)) + "|")
    for which in ("best", "validated"):
        r = res[which]
        print(f"| {which} | {r['generation']} | {r['chosen_by']:.3f} | {r['validation']:.3f} | "
              f"{r['fresh']:.3f} ± {r['fresh_se']:.3f} |"
              + "".join(f" {100 * r[k]:.0f} % |" for k in keys))
    print(f"validated less best on the fresh episodes (paired): {res['fresh_paired_diff']:+.3f}"
          f" ± {res['fresh_paired_se']:.3f}\n")


if __name__ == "__main__":
    sys.exit(main())
