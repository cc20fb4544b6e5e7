"""What a gym run leaves: the best centre as ``policy.npz``, ``policy.py`` and ``policy.onnx``.

The best centre is the distribution mean whose evaluation on ``problem.eval_episodes`` unseen
episodes scored the highest mean return, with the normaliser it was evaluated with (ARS V2's
mean and std frozen into the file). ``policy.onnx`` needs the ``onnx`` extra; without it the
run logs one line and keeps the other two.
"""

from __future__ import annotations

from typing import Any


def write_policy(ctx: Any) -> None:
    """``policy.npz``/``.py``/``.onnx`` of the best centre so far (every checkpoint)."""
    from evomotion.core.policies.export import export_policy

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
    export_policy(ctx.out_dir, problem.policy, state.best_x, state.best_obs_mean,
                  state.best_obs_std, formats)


def finalize(ctx: Any) -> int | None:
    write_policy(ctx)
    s = ctx.state
    if s is not None and s.best_cost < float("inf"):
        ctx.log(f"gym {ctx.config.problem.env}: best centre return {-s.best_cost:.1f} "
                f"after {s.train_episodes} training episodes, {s.env_steps} environment steps; "
                "policy.npz, policy.py" + (", policy.onnx" if not ctx.cache.get("onnx_note")
                                          else ""))
    return None


def best_record(ctx: Any) -> dict[str, Any]:
    s = ctx.state
    if s is None:
        return {}
    return {"centre_return": -float(s.best_cost) if s.best_cost < float("inf") else None,
            "train_episodes": int(s.train_episodes), "env_steps": int(s.env_steps),
            "backend": ctx.problem.backend if ctx.problem is not None else None}
