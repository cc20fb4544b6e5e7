"""What a policy study's run leaves and reports: ``policy.npz``/``.py``/``.onnx`` of the centre
it exports (:func:`evomotion.studies.policy_search.exported`: the best validated centre with
``problem.validate_every``, else the best evaluated one), ``best.json``'s extras and the
closing log line. The studies' checkpoint and finalize hooks call these.
"""

from __future__ import annotations

from typing import Any

from evomotion.studies.policy_search import chosen_validated, exported


def best_record(ctx: Any) -> dict[str, Any]:
    """A policy study's ``best.json`` extras: the best centre's return, episodes, steps."""
    s = ctx.state
    if s is None:
        return {}
    best = -float(s.best_cost) if s.best_cost < float("inf") else None
    out: dict[str, Any] = {"centre_return": best, "train_episodes": int(s.train_episodes),
                           "env_steps": int(s.env_steps)}
    v = chosen_validated(s)
    if v is not None:  # the exported centre (policy_validation.py)
        out["validated"] = {"return": -float(v.cost), "generation": int(v.generation),
                            "episodes": int(getattr(ctx.config.problem, "validate_episodes",
                                                    0))}
    return out


def write_policy_files(ctx: Any, extra: dict[str, Any] | None = None) -> None:
    """``policy.npz``/``.py``/``.onnx`` of the run's best centre so far (the problem's
    ``policy`` spec, the normaliser it was evaluated with), and ``extra``'s JSON files
    (``{name: record}``); ``policy.onnx`` is skipped with one note without the ``onnx``
    extra. A study's checkpoint hook."""
    import json
    from pathlib import Path

    from evomotion.core.policies.export import export_policy
    from evomotion.outfile import atomic_write_text

    state, problem = ctx.state, ctx.problem
    if state is None or problem is None or ctx.out_dir is None or \
            not state.best_cost < float("inf"):
        return
    formats: tuple[str, ...] = ("npz", "py", "onnx")
    try:
        import onnx  # noqa: F401
    except ImportError:
        formats = ("npz", "py")
        if not ctx.cache.get("onnx_note"):
            ctx.log("note: policy.onnx not written (pip install 'evomotion[onnx]')")
            ctx.cache["onnx_note"] = True
    # a problem that searches other numbers than the policy's (a symmetric controller's)
    # maps them: ``policy_params(genomes)``
    x, _, obs_mean, obs_std = exported(state)
    params = problem.policy_params(x) if hasattr(problem, "policy_params") else x
    export_policy(ctx.out_dir, problem.policy, params, obs_mean, obs_std, formats)
    for name, record in (extra or {}).items():
        atomic_write_text(Path(ctx.out_dir) / name, json.dumps(record, indent=1) + "\n")


def log_best_centre(ctx: Any, study: str, also: tuple[str, ...] = ()) -> None:
    """The closing log line of a robot's policy study (humanoid-balance, humanoid-walk): the
    best centre's score and the files written (``also``: the study's own, where present)."""
    s = ctx.state
    if s is not None and s.best_cost < float("inf"):
        v = chosen_validated(s)
        what = (f"best validated centre score {-v.cost:.3f} (generation {v.generation})"
                if v is not None else f"best centre score {-s.best_cost:.3f}")
        ctx.log(f"{study}: {what} after "
                f"{s.train_episodes} training episodes; policy.npz, policy.py, policy.json"
                + (", policy.onnx" if not ctx.cache.get("onnx_note") else "")
                + "".join(f", {f}" for f in also
                          if ctx.out_dir is not None and (ctx.out_dir / f).is_file())
                + f"; evomotion {study} compare RUN measures it")
