"""The Python API of the run loop: :func:`run` a study or your own problem, :func:`load_run`.

``evomotion.run`` is ``evomotion run`` as a function: the same run folder (config.toml,
log.txt, stats.csv, best.json, checkpoints, plots), the same stop rules, evaluators and resume,
for a registered study (by name or :class:`~evomotion.studies.base.Study`) or for any object
that follows the :class:`~evomotion.core.problem.Problem` protocol (``genome``, ``sense``,
``metric_names``, ``evaluate``). ``config`` is a dict of sections (``{"algorithm": {...},
"run": {...}, "problem": {...}}``) checked like a TOML config file: an unknown key is a
one-line :class:`~evomotion.errors.InputError` naming it. Without ``out_dir`` the run stays in
memory (:func:`run_in_memory`, re-exported from :mod:`evomotion.run.in_memory`: the one
in-memory runner, which the studies' experiments use with a typed config and a built problem).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.core.problem import Problem
from evomotion.errors import InputError
from evomotion.run.in_memory import GivenProblem, run_in_memory
from evomotion.run.runner import RunResult
from evomotion.studies.base import Study
from evomotion.textio import read_file_bytes, read_json

MAX_LOG_BYTES = 64 * 1024 * 1024


@dataclass(frozen=True)
class NoProblemConfig:
    """The ``[problem]`` section of a problem given as an object: it has no keys."""


def problem_study(problem: Problem, name: str | None = None) -> Study:
    """A :class:`~evomotion.studies.base.Study` around a problem object (no presets, no
    hooks; every registered optimizer; ``name`` defaults to the problem's class name)."""
    from evomotion.core.problem import GenomeSpec

    for attr in ("genome", "sense", "evaluate"):
        if not hasattr(problem, attr):
            raise InputError(f"evomotion.run: the problem has no {attr!r}; expected an object "
                             "with genome, sense, metric_names and evaluate(genomes) (see "
                             "evomotion.Problem)")
    if not isinstance(problem.genome, GenomeSpec):
        raise InputError(f"evomotion.run: problem.genome must be an evomotion.GenomeSpec, got "
                         f"{type(problem.genome).__name__}")
    if problem.sense not in ("min", "max"):
        raise InputError(f"evomotion.run: problem.sense must be 'min' or 'max', got "
                         f"{problem.sense!r}")
    names = getattr(problem, "metric_names", ())
    if not (isinstance(names, tuple | list) and all(isinstance(n, str) for n in names)):
        raise InputError("evomotion.run: problem.metric_names must be a tuple of metric names")
    if not callable(problem.evaluate):
        raise InputError("evomotion.run: problem.evaluate must be callable")
    label = name or type(problem).__name__
    return Study(name=label, description=f"{label} (a problem given as a Python object)",
                 problem_config=NoProblemConfig, make_problem=GivenProblem(problem))


def _study_of(problem_or_study: Any) -> Study:
    if isinstance(problem_or_study, Study):
        return problem_or_study
    if isinstance(problem_or_study, str):
        from evomotion.studies import get_study

        return get_study(problem_or_study)
    return problem_study(problem_or_study)


def run(problem_or_study: Any, config: dict[str, Any] | None = None,
        out_dir: str | Path | None = None, *, preset: str | None = None,
        resume: bool = False, quiet: bool = True) -> RunResult:
    """Run ``problem_or_study`` (a study name, a :class:`Study` or a problem object) with
    ``config`` (sections ``algorithm``, ``run``, ``problem``; the study's defaults fill the
    rest) through the run loop. With ``out_dir`` the run folder is written there (an empty or
    new folder); ``resume=True`` continues the interrupted run in ``out_dir`` with its saved
    config (``config`` may then raise limits such as ``run.generations``). ``quiet=False``
    shows the progress bar. Returns the :class:`~evomotion.run.runner.RunResult` (best
    genome, fitness, metrics, stop reason, generation, exit code)."""
    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study

    study = _study_of(problem_or_study)
    if config is not None and not isinstance(config, dict):
        raise InputError(f"evomotion.run: config must be a dict of sections, got "
                         f"{type(config).__name__}")
    values = dict(config or {})
    for key in ("study", "preset"):
        if key in values:
            raise InputError(f"evomotion.run: config[{key!r}]: give the study as the first "
                             "argument and the preset as preset=")
    if preset is not None and not isinstance(preset, str):
        raise InputError(f"evomotion.run: preset must be a name, got {preset!r}")
    if isinstance(problem_or_study, str):  # a preset may be another study
        from evomotion.studies import get_study, study_with_preset

        study, preset = study_with_preset(problem_or_study, preset)
        if resume and out_dir is not None and (Path(out_dir) / "config.toml").is_file():
            from evomotion.run.config import config_from_run_dir

            name = config_from_run_dir(Path(out_dir))[0]  # its preset's study
            if name in study.preset_studies.values():
                study = get_study(name)
    if resume:
        from evomotion.run.resume import resume_config

        if out_dir is None:
            raise InputError("evomotion.run: resume=True needs the out_dir of the run")
        changes = {}
        for section, keys in values.items():
            if not isinstance(keys, dict):
                raise InputError(f"evomotion.run: config[{section!r}] must be a dict")
            changes.update({f"{section}.{k}": v for k, v in keys.items()})
        study, cfg = resume_config(Path(out_dir), study, changes)
        return run_study(study, cfg, Path(out_dir), quiet=quiet, resume=True)
    cfg = resolve_config(study, None, (), preset=preset, values=values)
    if out_dir is None:
        return run_in_memory(cfg, make_problem=study.make_problem, algorithms=study.algorithms)
    return run_study(study, cfg, Path(out_dir), quiet=quiet)


def _read_toml(path: Path) -> dict[str, Any]:
    from evomotion.run.config import load_toml

    return load_toml(path)


@dataclass(frozen=True)
class Run:
    """A run folder as data: ``config`` (the sections of config.toml, as the study reads them
    now: :func:`evomotion.run.config.as_now`), ``stats`` (column ->
    array of stats.csv), ``best`` (best.json, ``None`` before the first checkpoint),
    ``artifacts`` (file name -> path of everything else the run wrote: best.motion, plots,
    videos, ...), ``physics`` (physics.json of the MuJoCo studies) and the ``log`` lines."""

    path: Path
    study: str
    config: dict[str, Any]
    stats: dict[str, np.ndarray]
    best: dict[str, Any] | None
    artifacts: dict[str, Path] = field(default_factory=dict)
    physics: dict[str, Any] | None = None
    log: tuple[str, ...] = ()

    @property
    def best_fitness(self) -> float | None:
        return None if self.best is None else float(self.best["fitness"])

    @property
    def best_genome(self) -> np.ndarray | None:
        return None if self.best is None else np.asarray(self.best["genome"], dtype=float)


_ENGINE_FILES = {"config.toml", "stats.csv", "best.json", "physics.json", "log.txt", "run.lock"}


def load_run(path: str | Path) -> Run:
    """The run folder at ``path`` (finished, interrupted or running) as a :class:`Run`; a
    folder without a run is a one-line :class:`~evomotion.errors.InputError`."""
    from evomotion.run.stats import read_stats

    root = Path(path)
    cfg_path = root / "config.toml"
    if not cfg_path.is_file():
        raise InputError(f"{root}: not a run folder (no config.toml)")
    from evomotion.run.config import as_now

    # as the study reads it now: a study renamed since under its name now, keys added since
    # as the run had them (run/config.py ADDED_KEYS)
    config = as_now(_read_toml(cfg_path))
    stats_path = root / "stats.csv"
    stats = read_stats(stats_path) if stats_path.is_file() else {}
    best = _read_json(root / "best.json")
    physics = _read_json(root / "physics.json")
    log_path = root / "log.txt"
    log = tuple(read_file_bytes(log_path, "run log", MAX_LOG_BYTES).decode(
        "utf-8", "replace").splitlines()) if log_path.exists() else ()
    artifacts = {str(p.relative_to(root)): p for p in sorted(root.rglob("*"))
                 if p.is_file() and p.name not in _ENGINE_FILES
                 and "checkpoints" not in p.relative_to(root).parts
                 and not p.name.startswith(".")}
    return Run(root, str(config.get("study", "")), config, stats, best, artifacts, physics, log)


def _read_json(path: Path) -> dict[str, Any] | None:
    if not path.exists():
        return None
    data = read_json(path, "JSON file", finite=False)  # best.json may hold null, not NaN
    return data if isinstance(data, dict) else None

