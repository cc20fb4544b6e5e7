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

#: the keys a resume may change: limits, the evaluator, the loggers, videos (results stay
#: the same)
RESUME_KEYS = frozenset(f"run.{k}" for k in (
    "generations", "max_evaluations", "target", "stagnation_generations", "stagnation_eps",
    "wall_seconds", "checkpoint_every", "evaluator", "workers", "chunks_per_worker", "address",
    "loggers", "videos"))


def resume_config(run_dir: Path, study: Any = None,
                  changes: dict[str, Any] | None = None) -> tuple[Any, Config]:
    """(study, config) to resume ``run_dir`` with: its saved ``config.toml`` with
    ``changes`` (``{"section.key": value}``, only :data:`RESUME_KEYS`) applied, and the file
    rewritten when something changed (so ``evomotion resume`` later sees the new limits).
    ``study`` (a Study) defaults to the registered one the file names."""
    from evomotion.run.config import config_from_dict, config_from_run_dir, config_to_toml
    from evomotion.run.folder import atomic_write_text

    name, raw = config_from_run_dir(run_dir)
    if study is None:
        from evomotion.studies import get_study

        study = get_study(name)
    elif name != study.name:
        raise InputError(f"{run_dir}: the run is of study {name!r}, not {study.name!r}")
    raw.setdefault("run", {})
    for key, value in (changes or {}).items():
        if key not in RESUME_KEYS:
            raise InputError(f"{key}: resume only changes the limits, the evaluator, the "
                             f"loggers and videos ({', '.join(sorted(RESUME_KEYS))}); other "
                             "keys would make the results differ from an uninterrupted run")
        raw["run"][key.split(".", 1)[1]] = value
    config = config_from_dict(study, raw)
    if changes:
        atomic_write_text(Path(run_dir) / "config.toml", config_to_toml(config))
    return study, config


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
        if key not in recorded and now[key] == _field_default(config, key):
            continue  # a key added after the run started, at its default: same results
        if recorded.get(key) != now.get(key):
            raise InputError(
                f"{run_dir}: resume cannot change {key} (the run has {recorded.get(key)!r}, "
                f"now {now.get(key)!r}); the results would differ from an uninterrupted run "
                "(start a new run instead)")


def _field_default(config: Config, key: str) -> Any:
    """The dataclass default of ``algorithm.X`` / ``problem.X`` (a sentinel when none)."""
    section, _, name = key.partition(".")
    obj = getattr(config, section, None)
    if obj is None or not dataclasses.is_dataclass(obj) or "." in name:
        return _NO_DEFAULT
    for f in dataclasses.fields(obj):
        if f.name == name:
            if f.default is not dataclasses.MISSING:
                return list(f.default) if isinstance(f.default, tuple) else f.default
            if f.default_factory is not dataclasses.MISSING:
                return f.default_factory()
    return _NO_DEFAULT


_NO_DEFAULT = object()


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
                OverflowError, MemoryError) as e:
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
