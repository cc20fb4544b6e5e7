"""Resuming a run folder: the newest valid checkpoint, checked against the run's config.

A damaged checkpoint (see :mod:`.checkpoint`) falls back to the newest valid one before it, in
one log line, and the checkpoints after it are removed (they belong to the lost steps); a
checkpoint whose recorded config differs from the run's in a key that changes results (the
seed, the study, any ``[algorithm]`` or ``[problem]`` key) is refused, naming the key.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

from evomotion.core.state import rng_from_state
from evomotion.errors import InputError
from evomotion.run.checkpoint import NAME, CheckpointError, candidates, load_checkpoint
from evomotion.run.config import Config
from evomotion.run.driver import Driver


def config_record(config: Config) -> dict[str, Any]:
    """What a checkpoint records of the config: the keys a resume may not change."""
    return {"study": config.study, "run.seed": config.run.seed,
            **{f"algorithm.{k}": v for k, v in _flat(dataclasses.asdict(config.algorithm))},
            **{f"problem.{k}": v for k, v in _flat(dataclasses.asdict(config.problem))}}


def _flat(d: dict, prefix: str = ""):
    for k, v in d.items():
        if isinstance(v, dict):
            yield from _flat(v, f"{prefix}{k}.")
        else:
            yield f"{prefix}{k}", list(v) if isinstance(v, tuple) else v


def check_same_config(recorded: Any, config: Config, run_dir: Path) -> None:
    if recorded is None:
        return  # written before checkpoints recorded their config
    if not isinstance(recorded, dict):
        raise CheckpointError("config: expected an object")
    now = config_record(config)
    for key in sorted(set(recorded) | set(now)):
        if recorded.get(key) != now.get(key):
            raise InputError(
                f"{run_dir}: resume cannot change {key} (the run has {recorded.get(key)!r}, "
                f"now {now.get(key)!r}); the results would differ from an uninterrupted run "
                "(start a new run instead)")


def restore(run_dir: Path, driver: Driver, config: Config) -> tuple[Any, Any, dict, list[str]]:
    """``(state, rng, counters, log lines)`` of the newest valid checkpoint of ``run_dir``
    (the lines say which damaged checkpoints were skipped; log them after the log is cut back
    to the checkpoint)."""

    def accept(arrays: dict, meta: dict) -> tuple[Any, Any]:
        check_same_config(meta.get("config"), config, run_dir)
        st_a = {k[6:]: v for k, v in arrays.items() if k.startswith("state.")}
        st_m = {k[6:]: v for k, v in meta.items() if k.startswith("state.")}
        try:
            state = driver.restore(st_a, st_m)
            driver.check_state(state)
            rng = rng_from_state(meta["rng"])
        except (KeyError, TypeError, ValueError, AttributeError, IndexError,
                OverflowError) as e:
            raise CheckpointError(f"the state does not fit this run ({type(e).__name__}: "
                                  f"{str(e)[:120]})") from None
        return state, rng

    names = candidates(run_dir)
    _, meta, (state, rng), notes = load_checkpoint(run_dir, accept, names)
    lines = [f"warning: {line}; skipped" for line in notes]
    if notes:
        used = f"gen-{meta['generation']:06d}.json"
        lines.append(f"resuming from the newest valid checkpoint, checkpoints/{used}")
        newer = [n for n in names if int(NAME.fullmatch(n)[1]) > meta["generation"]]
        for n in newer:
            (run_dir / "checkpoints" / n).unlink(missing_ok=True)
            (run_dir / "checkpoints" / n.replace(".json", ".npz")).unlink(missing_ok=True)
    return state, rng, meta["counters"], lines
