"""What a gym run leaves: the best centre as ``policy.npz``, ``policy.py`` and ``policy.onnx``.

The best centre is the distribution mean whose evaluation on ``problem.eval_episodes`` unseen
episodes scored the highest mean return (with ``problem.validate_every``: the best on the
fixed validation episodes, studies/policy_validation.py), with the normaliser it was evaluated
with (ARS V2's mean and std frozen into the file). ``policy.onnx`` needs the ``onnx`` extra;
without it the run logs one line and keeps the other two.
"""

from __future__ import annotations

from typing import Any


def write_policy(ctx: Any) -> None:
    """``policy.npz``/``.py``/``.onnx`` of the best centre so far (every checkpoint)."""
    from evomotion.studies.policy_files import write_policy_files

    write_policy_files(ctx)


def finalize(ctx: Any) -> int | None:
    write_policy(ctx)
    from evomotion.studies.policy_search import chosen_validated, exported

    s = ctx.state
    if s is not None and s.best_cost < float("inf"):
        _, cost, _, _ = exported(s)
        what = "validated centre" if chosen_validated(s) is not None else "centre"
        ctx.log(f"gym {ctx.config.problem.env}: best {what} return {-cost:.1f} "
                f"after {s.train_episodes} training episodes, {s.env_steps} environment steps; "
                "policy.npz, policy.py" + (", policy.onnx" if not ctx.cache.get("onnx_note")
                                          else ""))
    return None


def best_record(ctx: Any) -> dict[str, Any]:
    from evomotion.studies.policy_files import best_record as policy_best

    out = policy_best(ctx)
    if out:
        out["backend"] = ctx.problem.backend if ctx.problem is not None else None
    return out
