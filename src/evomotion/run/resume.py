"""Resuming a run folder: the newest valid checkpoint, checked against the run's config.

A damaged checkpoint (see :mod:`.checkpoint`) falls back to the newest valid one before it, in
one log line, and the checkpoints after it are removed (they belong to the lost steps); a
checkpoint whose recorded config differs from the run's in a key that changes results (the
seed, the study, any ``[algorithm]`` or ``[problem]`` key) is refused, naming the key.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

from evomotion.core.state import rng_from_state
from evomotion.errors import InputError
from evomotion.run.checkpoint import NAME, CheckpointError, candidates, load_checkpoint
from evomotion.run.config import ADDED_KEYS, Config, current_study_name
from evomotion.run.contracts import LoopStudy
from evomotion.run.counters import Counters
from evomotion.run.driver import Driver
from evomotion.run.folder import clean_temporaries
from evomotion.run.moved_keys import moved_record
from evomotion.run.run_state import RunFiles, RunState
from evomotion.run.stopping import limit_reached

#: the stop reasons a resume with a raised limit continues from
LIMIT_REASONS = ("generations", "max_evaluations", "target", "wall_seconds")
#: the keys a resume may change: limits, the evaluator, the loggers, videos (results stay
#: the same)
RESUME_KEYS = frozenset(f"run.{k}" for k in (
    "generations", "max_evaluations", "target", "stagnation_generations", "stagnation_eps",
    "wall_seconds", "checkpoint_every", "evaluator", "workers", "chunks_per_worker", "address",
    "loggers", "videos"))


def resume_config(run_dir: Path, study: Any = None,
                  changes: dict[str, Any] | None = None,
                  resolve: Callable[[str], Any] | None = None) -> tuple[Any, Config]:
    """(study, config) to resume ``run_dir`` with: its saved ``config.toml`` with
    ``changes`` (``{"section.key": value}``, only :data:`RESUME_KEYS`) applied, and the file
    rewritten when something changed (so ``evomotion resume`` later sees the new limits).
    ``study`` (a Study) is the run's study; without it, ``resolve(name)`` finds the study the
    file names (the caller's registry, e.g. :func:`evomotion.studies.get_study`)."""
    from evomotion.outfile import atomic_write_text
    from evomotion.run.config import config_from_dict, config_from_run_dir, config_to_toml

    name, raw = config_from_run_dir(run_dir)
    if study is None:
        if resolve is None:
            raise ValueError("resume_config: give the study or a resolver of study names")
        study = resolve(name)
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


def _flat(d: dict[str, Any], prefix: str = "") -> Iterator[tuple[str, Any]]:
    for k, v in d.items():
        if isinstance(v, dict):
            yield from _flat(v, f"{prefix}{k}.")
        else:
            yield f"{prefix}{k}", list(v) if isinstance(v, tuple) else v


def check_same_config(recorded: Any, config: Config, run_dir: Path,
                      moved: Mapping[str, str] | None = None) -> None:
    """Refuse a checkpoint recorded with another config; ``moved``: the keys the study moved
    since (``Study.moved_keys``), compared at their new place."""
    if recorded is None:
        return  # written before checkpoints recorded their config
    if not isinstance(recorded, dict):
        raise CheckpointError("config: expected an object")
    now = config_record(config)
    if isinstance(recorded.get("study"), str):  # a study renamed since (run/config.py)
        problem = [k.partition(".")[2] for k in recorded if k.startswith("problem.")]
        recorded = {**recorded, "study": current_study_name(recorded["study"], problem)}
        for section, keys in ADDED_KEYS.get(recorded["study"], {}).items():
            recorded = {**{f"{section}.{k}": v for k, v in keys.items()}, **recorded}
    if moved:
        recorded = moved_record(recorded, moved, now)
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


def _generation(name: str) -> int:
    """The generation of a checkpoint's name (``gen-000012.json``: 12)."""
    found = NAME.fullmatch(name)
    return int(found[1]) if found else -1


def restore(run_dir: Path, driver: Driver, config: Config,
            moved: Mapping[str, str] | None = None) -> tuple[Any, Any, dict, list[str]]:
    """``(state, rng, counters, log lines)`` of the newest valid checkpoint of ``run_dir``
    (the lines say which damaged checkpoints were skipped; log them after the log is cut back
    to the checkpoint); ``moved``: see :func:`check_same_config`."""

    def accept(arrays: dict, meta: dict) -> tuple[Any, Any]:
        check_same_config(meta.get("config"), config, run_dir, moved)
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
        newer = [n for n in names if _generation(n) > meta["generation"]]
        for n in newer:
            (run_dir / "checkpoints" / n).unlink(missing_ok=True)
            (run_dir / "checkpoints" / n.replace(".json", ".npz")).unlink(missing_ok=True)
    return state, rng, meta["counters"], lines


def resume_run(study: LoopStudy, config: Config, problem: Any, driver: Driver, out_dir: Path,
               files: RunFiles) -> tuple[RunState, bool, int]:
    """The run restored from its newest valid checkpoint, whether it only has its final
    artifacts left to write, and how many temporary files were cleaned; the files are cut
    back to the checkpoint."""
    log = files.log
    moved = getattr(study, "moved_keys", None)  # a Study's (evomotion.studies.base)
    state, rng, doc, notes = restore(out_dir, driver, config, moved)
    c = Counters.from_json(doc)
    cleaned = clean_temporaries(out_dir)
    done = c.stop_reason
    finish_only = False  # a resume that only writes the final artifacts
    if done not in (None, "interrupted"):
        ended = driver.stop(state) is not None
        sgn = -1.0 if driver.sense == "max" else 1.0
        limit = limit_reached(config, c, driver.best(state)[1], sgn)
        raised = done in LIMIT_REASONS and limit is None and not ended  # a limit raised
        if c.finished is False and not raised:
            finish_only = True  # stopped while writing the final artifacts
        elif ended or limit:
            raise InputError(f"{out_dir}: the run already finished ({done}); " + (
                "it cannot be continued" if ended else
                "raise its limit to continue, e.g. --set run.generations=N"))
    c.stop_reason, c.reason_recorded = (done if finish_only else None), True
    c.finished = None
    files.stats.truncate(c.stats_offset)
    if files.history is not None:
        files.history.truncate(c.history_offset)
    kept = log.lines_after(c.log_offset)  # the log keeps the stopped session's lines
    for line in notes:
        log(line)
    since = (f"; the {kept} line{'s' if kept != 1 else ''} above since that checkpoint are the "
             "stopped session's" + ("" if finish_only else
                                    f" (its generations after {c.generation} run again)")
             ) if kept else ""
    log(f"resumed at generation {c.generation} to write the final artifacts (the run was "
        "stopped while writing them)" + since if finish_only else
        f"resumed at generation {c.generation} with evaluator {config.run.evaluator}" + since)
    run = RunState(study, config, problem, driver, state, rng, c, log, out_dir)
    return run, finish_only, cleaned
