"""A policy run's distribution centre at its latest checkpoint as a run folder of its own,
so that ``compare``, ``walk_export_choice.py``, ``walk_fine_tune.py`` or ``problem.start_policy``
can take it beside the run's export (the best centre by its noisy per-generation score).

    python benchmarks/export_centre.py RUN OUT

``OUT`` gets RUN's ``config.toml`` and ``physics.json`` and a ``policy.npz`` of the latest
checkpoint's centre (a symmetric run's free numbers expanded) with the normaliser of every
state seen so far (what the next generation would evaluate it with).
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("run", type=Path)
    ap.add_argument("out", type=Path)
    a = ap.parse_args()

    from evomotion.core.policies.export import write_policy_npz
    from evomotion.core.policies.normalizer import RunningStats
    from evomotion.errors import InputError
    from evomotion.run.checkpoint import candidates, read_checkpoint
    from evomotion.run.config import config_from_dict, config_from_run_dir
    from evomotion.studies import get_study
    from evomotion.studies.policy_search import normaliser

    try:
        if a.out.resolve() == a.run.resolve():
            raise InputError(f"OUT {a.out}: expected another folder than RUN's")
        name, raw = config_from_run_dir(a.run)
        study = get_study(name)
        cfg = config_from_dict(study, raw)
        problem = study.make_problem(cfg.problem)
        names = candidates(a.run)
        if not names:
            raise InputError(f"{a.run}: no checkpoint")
        arrays, meta = read_checkpoint(a.run, names[0])
        missing = {"state.opt.center", "state.obs.count"} - set(arrays)
        if missing:
            raise InputError(f"{a.run}: its checkpoint holds no {sorted(missing)[0]} (expected "
                             "a policy search by an evolution strategy, not CMA-ES)")
    except (InputError, ValueError, OSError) as e:  # CheckpointError is a ValueError
        print(f"error: {e}", file=sys.stderr)
        return 2
    centre = arrays["state.opt.center"]
    params = problem.policy_params(centre) if hasattr(problem, "policy_params") else centre
    stats = RunningStats(arrays["state.obs.count"], arrays["state.obs.mean"],
                         arrays["state.obs.m2"])
    mean, std = normaliser(stats, problem.normalize)
    a.out.mkdir(parents=True, exist_ok=True)
    for f in ("config.toml", "physics.json"):
        if (a.run / f).is_file():
            shutil.copyfile(a.run / f, a.out / f)
    write_policy_npz(a.out / "policy.npz", problem.policy, params, mean, std)
    print(f"wrote {a.out / 'policy.npz'}: the centre at generation {meta['generation']}")
    if hasattr(problem, "sim"):
        problem.sim.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
