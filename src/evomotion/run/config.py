"""Typed run configuration: dataclass defaults < study defaults < TOML file < ``--set``.

The top level has three sections: ``[run]`` (:class:`RunSection`), ``[algorithm]`` (the
dataclass registered for ``algorithm.name`` in :data:`evomotion.core.algorithms.ALGORITHMS`)
and ``[problem]`` (the study's ``problem_config``). Unknown keys and wrong types raise
:class:`~evomotion.errors.InputError` naming the key and listing the valid ones.
"""

from __future__ import annotations

import dataclasses
import re
import tomllib
import types
import typing
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import tomli_w

from evomotion.core.algorithms import ALGORITHMS
from evomotion.core.registry import lookup
from evomotion.errors import FileFormatError, InputError


@dataclass(frozen=True)
class RunSection:
    """Run control. ``0`` disables a numeric limit; ``target`` is in the problem's sense."""

    seed: int = 0
    generations: int = 100
    max_evaluations: int = 0
    target: float | None = None
    stagnation_generations: int = 0
    stagnation_eps: float = 1e-12
    wall_seconds: float = 0.0
    checkpoint_every: int = 10
    evaluator: str = "serial"
    workers: int = 0
    chunks_per_worker: int = 4
    address: str = ""

    def validate(self) -> None:
        for k in ("generations", "max_evaluations", "stagnation_generations", "workers",
                  "checkpoint_every"):
            if getattr(self, k) < 0:
                raise InputError(f"run.{k} must be >= 0, got {getattr(self, k)}")
        if self.chunks_per_worker < 1:
            raise InputError(f"run.chunks_per_worker must be >= 1, got {self.chunks_per_worker}")
        if self.wall_seconds < 0:
            raise InputError(f"run.wall_seconds must be >= 0, got {self.wall_seconds}")
        from evomotion.run.evaluators import EVALUATORS

        lookup(EVALUATORS, "evaluator", self.evaluator)


@dataclass(frozen=True)
class Config:
    study: str
    run: RunSection
    algorithm: Any
    problem: Any
    preset: str | None = None  # the preset it was resolved with (recorded in config.toml)


def parse_value(text: str) -> Any:
    """A ``--set`` value: a TOML literal (``3``, ``0.5``, ``true``, ``[1, 2]``) or a bare string."""
    if text.strip().lower() == "none":
        return None
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def load_toml(path: Path) -> dict[str, Any]:
    try:
        text = Path(path).read_text()
    except OSError as e:
        raise InputError(f"{path}: cannot read config ({e.strerror})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        m = re.search(r"^(.*) \(at line (\d+), column (\d+)\)$", str(e))
        if m:
            raise FileFormatError(path, int(m[2]), f"column {m[3]}: invalid TOML: {m[1]}") from None
        raise FileFormatError(path, None, f"invalid TOML: {e}") from None


def _merge(base: dict, extra: dict) -> dict:
    out = dict(base)
    for k, v in extra.items():
        out[k] = _merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


def apply_override(raw: dict, item: str) -> dict:
    if "=" not in item:
        raise InputError(f"--set expects KEY=VALUE (for example run.seed=3), got {item!r}")
    key, _, val = item.partition("=")
    parts = key.strip().split(".")
    if len(parts) < 2 or not all(parts):
        raise InputError(f"--set key must be SECTION.NAME (run, algorithm, problem), got {key!r}")
    node: dict = {}
    leaf = node
    for p in parts[:-1]:
        leaf[p] = {}
        leaf = leaf[p]
    leaf[parts[-1]] = parse_value(val)
    return _merge(raw, node)


def _check_type(value: Any, tp: Any, key: str) -> Any:
    origin = typing.get_origin(tp)
    if tp is Any:
        return value
    if origin in (typing.Union, types.UnionType):
        args = typing.get_args(tp)
        if value is None and type(None) in args:
            return None
        errors = []
        for a in args:
            if a is type(None):
                continue
            try:
                return _check_type(value, a, key)
            except InputError as e:
                errors.append(e)
        raise errors[0]
    if tp is float and isinstance(value, int | float) and not isinstance(value, bool):
        return float(value)
    if tp is int and isinstance(value, int) and not isinstance(value, bool):
        return value
    if tp is bool and isinstance(value, bool):
        return value
    if tp is str and isinstance(value, str):
        return value
    if (origin is dict or tp is dict) and isinstance(value, dict):
        return dict(value)
    if (origin in (tuple, list) or tp in (tuple, list)) and isinstance(value, list | tuple):
        args = [a for a in typing.get_args(tp) if a is not Ellipsis]
        items = [_check_type(v, args[0], key) for v in value] if args else list(value)
        return tuple(items) if (origin is tuple or tp is tuple) else items
    name = getattr(tp, "__name__", str(tp))
    raise InputError(f"{key}: expected {name}, got {type(value).__name__} {value!r}")


def build_section(cls: type, values: dict[str, Any], section: str) -> Any:
    """Instantiate dataclass ``cls`` from ``values`` with strict key and type checks."""
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    kwargs = {}
    for k, v in values.items():
        if k not in fields:
            raise InputError(f"unknown key '{section}.{k}'; valid keys: "
                             + ", ".join(sorted(fields)))
        kwargs[k] = _check_type(v, hints[k], f"{section}.{k}")
    try:
        obj = cls(**kwargs)
    except (TypeError, ValueError) as e:
        raise InputError(f"[{section}]: {e}") from None
    if hasattr(obj, "validate"):
        try:
            obj.validate()
        except InputError:
            raise
        except (ValueError, KeyError) as e:
            raise InputError(str(e).strip("'\"")) from None
    return obj


def study_algorithms(study: Any) -> dict[str, type]:
    """``algorithm.name`` -> config dataclass of every method ``study`` accepts: its own
    (``study.algorithms``) and the registered optimizers it allows (``study.core_algorithms``)."""
    allowed = getattr(study, "core_algorithms", None)
    out = {n: cls for n, (cls, _f) in ALGORITHMS.items() if allowed is None or n in allowed}
    out.update({n: cls for n, (cls, _f) in getattr(study, "algorithms", {}).items()})
    return out


def default_algorithm(study: Any) -> str:
    """The method a study runs when ``algorithm.name`` is not given."""
    name = study.defaults.get("algorithm", {}).get("name")
    return name or next(iter(study_algorithms(study)))


def resolve_config(study: Any, file: Path | None = None,
                   overrides: list[str] | tuple[str, ...] = (),
                   preset: str | None = None) -> Config:
    """Resolve the full config of ``study`` (a :class:`~evomotion.studies.base.Study`):
    dataclass defaults < study defaults < ``preset`` < TOML ``file`` < ``overrides``."""
    user: dict[str, Any] = {}
    if file is not None:
        user = load_toml(file)
        user.pop("study", None)
        user.pop("preset", None)
    for item in overrides:
        user = apply_override(user, item)
    defaults = {k: dict(v) for k, v in study.defaults.items()}
    if preset is not None:
        presets = getattr(study, "presets", {})
        if preset not in presets:
            raise InputError(f"--preset: unknown preset {preset!r} for study {study.name!r}; "
                             f"available: {', '.join(presets) or 'none'}")
        defaults = _merge(defaults, presets[preset])
    default_alg = defaults.get("algorithm", {}).get("name") or default_algorithm(study)
    user_alg = user.get("algorithm", {}) if isinstance(user.get("algorithm"), dict) else {}
    if user_alg.get("name", default_alg) != default_alg:
        defaults.pop("algorithm", None)  # the study's tuning is for its own algorithm
    raw: dict[str, Any] = {"run": {}, "algorithm": {"name": default_alg}, "problem": {}}
    raw = _merge(_merge(raw, defaults), user)
    cfg = config_from_dict(study, raw)
    return dataclasses.replace(cfg, preset=preset)


def config_from_dict(study: Any, raw: dict[str, Any]) -> Config:
    extra = set(raw) - {"run", "algorithm", "problem", "study", "preset"}
    if extra:
        raise InputError(f"unknown section '{sorted(extra)[0]}'; valid sections: "
                         "algorithm, problem, run")
    for sec in ("run", "algorithm", "problem"):
        if not isinstance(raw.get(sec, {}), dict):
            raise InputError(f"'{sec}' must be a table of keys")
    run = build_section(RunSection, raw.get("run", {}), "run")
    run.validate()
    alg_raw = dict(raw.get("algorithm", {}))
    name = alg_raw.get("name", default_algorithm(study))
    alg_cls = lookup(study_algorithms(study), "algorithm", str(name))
    alg_raw["name"] = name
    algorithm = build_section(alg_cls, alg_raw, "algorithm")
    problem = build_section(study.problem_config, raw.get("problem", {}), "problem")
    preset = raw.get("preset")
    return Config(study=study.name, run=run, algorithm=algorithm, problem=problem,
                  preset=preset if isinstance(preset, str) else None)


def _strip_none(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {k: _strip_none(v) for k, v in obj.items() if v is not None}
    if isinstance(obj, list | tuple):
        return [_strip_none(v) for v in obj]
    return obj


def config_to_toml(cfg: Config) -> str:
    data = {"study": cfg.study, **({"preset": cfg.preset} if cfg.preset else {}),
            "run": dataclasses.asdict(cfg.run),
            "algorithm": dataclasses.asdict(cfg.algorithm),
            "problem": dataclasses.asdict(cfg.problem)}
    return tomli_w.dumps(_strip_none(data))


def config_from_run_dir(run_dir: Path) -> tuple[str, dict[str, Any]]:
    """Study name and raw config saved in a run folder (``config.toml``)."""
    path = Path(run_dir) / "config.toml"
    if not path.exists():
        raise InputError(f"{run_dir}: not a run folder (no config.toml)")
    raw = load_toml(path)
    if "study" not in raw:
        raise FileFormatError(path, None, "expected a top-level 'study' key")
    return raw["study"], raw
