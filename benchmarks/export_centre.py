"""A policy run's distribution centre at its latest checkpoint as a run folder of its own,
so that ``compare``, ``walk_export_choice.py``, ``walk_fine_tune.py`` or ``problem.start_policy``
can take it beside the run's export (the best centre by its noisy per-generation score, or
with ``problem.validate_every`` the best validated one).

    python benchmarks/export_centre.py RUN OUT [--which centre|best|validated]

``OUT`` gets RUN's ``config.toml`` and ``physics.json`` and a ``policy.npz`` (a symmetric run's
free numbers expanded) of, by ``--which``:

- ``centre`` (the default): the latest checkpoint's centre, with the normaliser of every
  state seen so far (what the next generation would evaluate it with);
- ``best``: the centre with the best single per-generation score, with the normaliser it was
  scored with (what the run exports without validation);
- ``validated``: the best validated centre (what a run with ``problem.validate_every`` exports).
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
    ap.add_argument("--which", choices=("centre", "best", "validated"), default="centre")
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
        need = {"centre": {"state.opt.center", "state.obs.count"},
                "best": {"state.best_x", "state.best_obs_mean"},
                "validated": {"state.valid.x", "state.valid.obs_mean"}}[a.which]
        missing = need - set(arrays)
        if missing:
            raise InputError(f"{a.run}: its checkpoint holds no {sorted(missing)[0]} (expected "
                             + ("a run with problem.validate_every" if a.which == "validated"
                                else "a policy search by an evolution strategy, not CMA-ES")
                             + ")")
    except (InputError, ValueError, OSError) as e:  # CheckpointError is a ValueError
        print(f"error: {e}", file=sys.stderr)
        return 2
    if a.which == "centre":
        centre = arrays["state.opt.center"]
        stats = RunningStats(arrays["state.obs.count"], arrays["state.obs.mean"],
                             arrays["state.obs.m2"])
        mean, std = normaliser(stats, problem.normalize)
        what = f"the centre at generation {meta['generation']}"
    else:
        key = "state.best_" if a.which == "best" else "state.valid."
        centre = arrays[key + "x"]
        mean, std = arrays[key + "obs_mean"], arrays[key + "obs_std"]
        what = (f"the best-scored centre (checkpoint at generation {meta['generation']})"
                if a.which == "best" else
                f"the best validated centre, of generation {meta['state.valid.generation']}")
    params = problem.policy_params(centre) if hasattr(problem, "policy_params") else centre
    a.out.mkdir(parents=True, exist_ok=True)
    for f in ("config.toml", "physics.json"):
        if (a.run / f).is_file():
            shutil.copyfile(a.run / f, a.out / f)
    write_policy_npz(a.out / "policy.npz", problem.policy, params, mean, std)
    print(f"wrote {a.out / 'policy.npz'}: {what}")
    if hasattr(problem, "sim"):
        problem.sim.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
