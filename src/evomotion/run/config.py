"""Typed run configuration: dataclass defaults < study defaults < the robot's < preset < TOML
file < ``--set``.

The top level has three sections: ``[run]`` (:class:`RunSection`), ``[algorithm]`` (the
dataclass registered for ``algorithm.name`` in :data:`evomotion.core.algorithms.ALGORITHMS`)
and ``[problem]`` (the study's ``problem_config``). Unknown keys and wrong types raise
:class:`~evomotion.errors.InputError` naming the key and listing the valid ones; a key the
study moved (``Study.moved_keys``) is read at its new place with a note (:mod:`.moved_keys`).

Nothing a user writes gets past as a traceback: the file is decoded as UTF-8 with a
``FILE:LINE`` error; every ``float`` field must be finite unless its field metadata documents
what ``inf`` means (:func:`evomotion.core.checks.inf_ok`), every ``int`` is 64-bit and never a
``bool``; each section's ``validate()`` checks its ranges (operator parameters against the
operator's signature); and :func:`evomotion.run.limits.check_memory` refuses a population
that cannot fit in the available memory before any array is allocated.
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
from evomotion.core.checks import ALLOW_INF, check_fields, check_number, check_text
from evomotion.core.registry import lookup
from evomotion.errors import FileFormatError, InputError
from evomotion.run.contracts import ConfiguredStudy
from evomotion.run.moved_keys import move_sources

#: a config file is refused above this size (it is a handful of keys)
MAX_CONFIG_BYTES = 1 << 20
#: ``run.workers`` and ``run.chunks_per_worker`` at most (process pools, cluster chunks)
MAX_WORKERS = 4096
MAX_CHUNKS_PER_WORKER = 1 << 16


@dataclass(frozen=True)
class RunSection:
    """Run control. ``0`` disables a numeric limit; ``target`` is in the problem's sense."""

    seed: int = 0  # the run's one seed, >= 0: the same seed gives the same run bit for bit
    generations: int = 100  # generations to run (0: no limit)
    max_evaluations: int = 0  # stop after this many evaluations (0: no limit)
    target: float | None = None  # stop once the best reaches it (fitness, the problem's sense)
    stagnation_generations: int = 0  # stop after N generations without improvement (0: never)
    stagnation_eps: float = 1e-12  # the least improvement of best or mean that counts, >= 0
    wall_seconds: float = 0.0  # stop after this much wall time (s; 0: no limit)
    checkpoint_every: int = 10  # a checkpoint every N generations (and at every stop)
    evaluator: str = "serial"  # serial | process | ray | dask: same results for one seed
    workers: int = 0  # evaluator workers, [0, 4096] (0: one per core)
    chunks_per_worker: int = 4  # work split in workers x this chunks per generation, >= 1
    address: str = ""  # ray / dask: the cluster's address (HOST:PORT; "": a new local one)
    history_every: int = 0  # population.bin every N generations (0: none; run/history.py)
    loggers: tuple[str, ...] = ()  # extra loggers beside stats.csv (run/loggers/)
    videos: bool = True  # the studies' MP4s at the end (false: skipped, logged; sim/render.py)

    def validate(self) -> None:
        check_fields(self, "run")
        for k in ("generations", "max_evaluations", "stagnation_generations", "workers",
                  "checkpoint_every", "history_every"):
            if getattr(self, k) < 0:
                raise InputError(f"run.{k} must be >= 0, got {getattr(self, k)}")
        if self.chunks_per_worker < 1:
            raise InputError(f"run.chunks_per_worker must be >= 1, got {self.chunks_per_worker}")
        if self.wall_seconds < 0:
            raise InputError(f"run.wall_seconds must be >= 0, got {self.wall_seconds}")
        check_number("run.seed", self.seed, lo=0, integer=True)  # numpy seeds are >= 0
        check_number("run.stagnation_eps", self.stagnation_eps, lo=0.0)
        check_number("run.workers", self.workers, lo=0, hi=MAX_WORKERS, integer=True)
        check_number("run.chunks_per_worker", self.chunks_per_worker, lo=1,
                     hi=MAX_CHUNKS_PER_WORKER, integer=True)
        from evomotion.run.evaluators import EVALUATORS

        lookup(EVALUATORS, "evaluator", self.evaluator)
        from evomotion.run.loggers import check_names

        check_names(self.loggers)


@dataclass(frozen=True)
class Config:
    study: str
    run: RunSection
    algorithm: Any
    problem: Any
    preset: str | None = None  # the preset it was resolved with (recorded in config.toml)


def parse_value(text: str) -> Any:
    """A ``--set`` value: a TOML literal (``3``, ``0.5``, ``true``, ``[1, 2]``, ``nan``,
    ``inf``; the field checks refuse the non-finite ones) or a bare string."""
    if text.strip().lower() == "none":
        return None
    if "\n" in text or "\r" in text:  # one value, not a TOML document
        return text
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except (tomllib.TOMLDecodeError, RecursionError):
        return text


def _decode(path: Path, data: bytes) -> str:
    """``data`` as UTF-8 (a BOM is dropped), or ``FILE:LINE: expected UTF-8 text``."""
    try:
        return data.decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError as e:
        start = data.rfind(b"\n", 0, e.start) + 1
        line = data.count(b"\n", 0, e.start) + 1
        column = len(data[start:e.start].decode("utf-8", errors="replace")) + 1
        raise FileFormatError(path, line, f"expected UTF-8 text (byte 0x{data[e.start]:02x} "
                                          f"at column {column})") from None


def load_toml(path: Path) -> dict[str, Any]:
    """The TOML document at ``path``; every problem with it is a one-line :class:`InputError`
    (unreadable, a directory, too large, not UTF-8, not TOML: ``FILE:LINE: ...``)."""
    from evomotion.textio import read_file_bytes

    path = Path(path)
    data = read_file_bytes(path, "TOML file", MAX_CONFIG_BYTES)
    text = _decode(path, data)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        m = re.search(r"^(.*) \(at line (\d+), column (\d+)\)$", str(e))
        if m:
            raise FileFormatError(path, int(m[2]), f"column {m[3]}: invalid TOML: {m[1]}") from None
        raise FileFormatError(path, None, f"invalid TOML: {e}") from None
    except RecursionError:
        raise FileFormatError(path, None, "invalid TOML: arrays or tables nested too "
                                          "deeply") from None


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


def _check_type(value: Any, tp: Any, key: str, allow_inf: bool = False) -> Any:
    """``value`` converted to type ``tp`` (ints to floats), or a one-line error naming ``key``.

    Floats must be finite unless ``allow_inf`` (the field's :func:`~evomotion.core.checks.inf_ok`
    metadata), ints are 64-bit and never bools, strings have no NUL characters."""
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
                return _check_type(value, a, key, allow_inf)
            except InputError as e:
                errors.append(e)
        raise errors[0]
    if tp is float and isinstance(value, int | float) and not isinstance(value, bool):
        check_number(key, value, allow_inf=allow_inf)
        return float(value)
    if tp is int and isinstance(value, int) and not isinstance(value, bool):
        check_number(key, value, integer=True)
        return value
    if tp is bool and isinstance(value, bool):
        return value
    if tp is str and isinstance(value, str):
        check_text(key, value)
        return value
    if tp is str and value is None:  # --set's bare "none" for a text key: the word
        return "none"
    if (origin is dict or tp is dict) and isinstance(value, dict):
        return dict(value)
    if (origin in (tuple, list) or tp in (tuple, list)) and isinstance(value, list | tuple):
        item_types = [a for a in typing.get_args(tp) if a is not Ellipsis]
        elems = [_check_type(v, item_types[0], f"{key}[{i}]", allow_inf)
                 for i, v in enumerate(value)] if item_types else list(value)
        return tuple(elems) if (origin is tuple or tp is tuple) else elems
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
        kwargs[k] = _check_type(v, hints[k], f"{section}.{k}", ALLOW_INF in fields[k].metadata)
    try:
        obj = cls(**kwargs)
    except (TypeError, ValueError) as e:
        raise InputError(f"[{section}]: {e}") from None
    if hasattr(obj, "validate"):
        try:
            obj.validate()
        except InputError:
            raise
        except (ValueError, KeyError, TypeError, ArithmeticError) as e:
            msg = str(e).strip("'\"")
            raise InputError(msg if msg.startswith(f"{section}.") else f"[{section}]: {msg}") \
                from None
    return obj


def study_algorithms(study: ConfiguredStudy) -> dict[str, type]:
    """``algorithm.name`` -> config dataclass of every method ``study`` accepts: its own
    (``study.algorithms``) and the registered optimizers it allows (``study.core_algorithms``)."""
    allowed = study.core_algorithms
    out = {n: cls for n, (cls, _f) in ALGORITHMS.items() if allowed is None or n in allowed}
    out.update({n: cls for n, (cls, _f) in study.algorithms.items()})
    return out


def defaults_entry(study: Any, robot: Any) -> Any:
    """The key of ``study.robot_defaults`` and ``robot_presets`` that ``robot`` (a value of
    ``problem.<study.defaults_key>``) reads: ``study.defaults_alias(robot)`` (gym: any version
    of a task reads its v5 id's) or ``robot`` itself."""
    alias = getattr(study, "defaults_alias", None)
    return alias(robot) if alias is not None and isinstance(robot, str) else robot


def default_algorithm(study: Any, robot: str | None = None) -> str:
    """The method a study runs when ``algorithm.name`` is not given; with ``robot`` (the value
    of ``problem.<study.defaults_key>``, ``""``: not given) the one its defaults choose."""
    robot = defaults_entry(study, robot)
    own = study.robot_defaults.get(robot, {}).get("algorithm", {}) if robot is not None else {}
    name = own.get("name") or study.defaults.get("algorithm", {}).get("name")
    return name or next(iter(study_algorithms(study)))


def _drop_other_operator_params(study: Any, defaults: dict, user_alg: dict,
                                default_alg: str) -> None:
    """A user who picks another crossover/mutation/selection than the defaults' drops the
    defaults' parameters of the replaced operator (they belong to it)."""
    alg = defaults.get("algorithm")
    cls = study_algorithms(study).get(default_alg)
    if not isinstance(alg, dict) or cls is None:
        return
    field_defaults = {f.name: f.default for f in dataclasses.fields(cls)}
    for op in ("crossover", "mutation", "selection"):
        if op in user_alg and user_alg[op] != alg.get(op, field_defaults.get(op)):
            alg.pop(f"{op}_params", None)


#: Old preset names and the names they have now (issue 32: "seed" is the random seed only;
#: the source paper's literal setting is ``--preset paper``). Old commands keep working.
OLD_PRESET_NAMES = {"seed": "paper"}


def current_preset_name(study: ConfiguredStudy, preset: str | None) -> str | None:
    """``preset`` under its name now: an old name (:data:`OLD_PRESET_NAMES`) becomes the new
    one when ``study`` has that preset and no preset of the old name."""
    presets = study.presets
    new = OLD_PRESET_NAMES.get(preset) if isinstance(preset, str) else None
    if new is not None and preset not in presets and new in presets:
        return new
    return preset


def resolve_config(study: ConfiguredStudy, file: Path | None = None,
                   overrides: list[str] | tuple[str, ...] = (),
                   preset: str | None = None,
                   values: dict[str, Any] | None = None) -> Config:
    """Resolve the full config of ``study`` (a :class:`~evomotion.studies.base.Study`):
    dataclass defaults < study defaults < the robot's (``study.robot_defaults`` for the
    configured ``problem.robot``, or ``problem.<study.defaults_key>``) < ``preset`` (and its
    setting on that robot, ``study.robot_presets``) < TOML
    ``file`` < ``values`` (sections as a dict, the Python API's ``config``) < ``overrides``;
    keys the study moved (``study.moved_keys``) are read at their new place, with a note
    (:mod:`.moved_keys`)."""
    layers: list[dict[str, Any]] = []  # each source alone: an old and a new key in one clash
    if file is not None:
        layers.append(saved_as_now(study, load_toml(file)))
        layers[-1].pop("study", None)
        layers[-1].pop("preset", None)
    if values:
        layers.append(dict(values))
    given: dict[str, Any] = {}
    for item in overrides:
        given = apply_override(given, item)
    layers.append(given)
    user: dict[str, Any] = {}
    for layer in layers:
        user = _merge(user, layer)
    defaults = {k: dict(v) for k, v in study.defaults.items()}
    robot = defaults_entry(study, configured_robot(user, study.defaults_key))
    # each method's tuning for a user who picks it: the study's, or one a layer above replaced
    tunings = {str(k): dict(v) for k, v in study.algorithm_tunings.items()}
    if isinstance(robot, str) and robot in study.robot_defaults:
        defaults, tunings = _layer_over(
            defaults, {k: dict(v) for k, v in study.robot_defaults[robot].items()}, tunings)
    preset = current_preset_name(study, preset)
    if preset is not None:
        presets = study.presets
        if preset not in presets:
            known = [*presets, *getattr(study, "preset_studies", {})]
            raise InputError(f"--preset: unknown preset {preset!r} for study {study.name!r}; "
                             f"available: {', '.join(known) or 'none'}")
        defaults, tunings = _layer_over(defaults, dict(presets[preset]), tunings)
        keyed = study.robot_presets.get(preset, {})  # the preset's setting on this robot
        if isinstance(robot, str) and robot in keyed:
            defaults, tunings = _layer_over(
                defaults, {k: dict(v) for k, v in keyed[robot].items()}, tunings)
    default_alg = defaults.get("algorithm", {}).get("name") or default_algorithm(study)
    user_alg = user.get("algorithm", {}) if isinstance(user.get("algorithm"), dict) else {}
    if study.moved_keys:  # the keys a study moved, read at their new place (one note each)
        name = str(user_alg.get("name", default_alg))
        *layers, defaults = move_sources([*layers, defaults], study.moved_keys,
                                         _sections(study, name), name)
        user = {}
        for layer in layers:
            user = _merge(user, layer)
        user_alg = user.get("algorithm", {}) if isinstance(user.get("algorithm"), dict) else {}
    tuned = default_alg  # the method whose tuning ``defaults`` holds
    if user_alg.get("name", default_alg) != default_alg:
        defaults.pop("algorithm", None)  # the study's tuning is for its own algorithm
        picked = user_alg.get("name")  # any value: the section's check reports a bad one
        if isinstance(picked, str) and picked in tunings:  # gym: ARS beside Hopper's CMA-ES
            defaults["algorithm"], tuned = dict(tunings[picked]), picked
    _drop_other_operator_params(study, defaults, user_alg, tuned)
    raw: dict[str, Any] = {"run": {}, "algorithm": {"name": default_alg}, "problem": {}}
    raw = _merge(_merge(raw, defaults), user)
    cfg = config_from_dict(study, raw)
    return dataclasses.replace(cfg, preset=preset)


def _layer_over(defaults: dict[str, Any], layer: dict[str, Any],
                tunings: dict[str, dict[str, Any]]
                ) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    """``layer`` (a robot's defaults, a preset) over ``defaults``; where it names another
    algorithm, the tuning below was for the other one: dropped, and kept in ``tunings`` by
    name for a user who picks that algorithm again."""
    below = defaults.get("algorithm", {})
    name = layer.get("algorithm", {}).get("name")
    if name is not None and name != below.get("name"):
        if below.get("name"):
            tunings = {**tunings, str(below["name"]): dict(below)}
        defaults = {k: v for k, v in defaults.items() if k != "algorithm"}
    return _merge(defaults, layer), tunings


def _sections(study: ConfiguredStudy, algorithm: str) -> dict[str, type] | None:
    """The dataclass of each section for method ``algorithm`` (None: an unknown method)."""
    algorithms = study_algorithms(study)
    if algorithm not in algorithms:
        return None
    return {"run": RunSection, "algorithm": algorithms[algorithm],
            "problem": study.problem_config}


def config_from_dict(study: Any, raw: dict[str, Any]) -> Config:
    if getattr(study, "moved_keys", None) and isinstance(raw.get("algorithm", {}), dict):
        name = str(raw.get("algorithm", {}).get("name", default_algorithm(study)))
        (raw,) = move_sources([raw], study.moved_keys, _sections(study, name), name)
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
    cfg = Config(study=study.name, run=run, algorithm=algorithm, problem=problem,
                 preset=preset if isinstance(preset, str) else None)
    from evomotion.run.limits import check_memory

    check_memory(study, cfg)  # what the config alone tells (the run loop checks again)
    return cfg


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


#: Studies renamed since run folders were written: (the name a folder records, a
#: ``[problem]`` key only the old study had, or None for any folder) -> the name now. Issue
#: 34: the closed-loop walk controller became ``humanoid-walk`` (it was
#: ``humanoid-omniwalk``) and the open-loop walk ``humanoid-walk-open-loop`` (an open-loop
#: folder records ``humanoid-walk`` and its ``walk_s``).
RENAMED_STUDIES: tuple[tuple[str, str | None, str], ...] = (
    ("humanoid-omniwalk", None, "humanoid-walk"),
    ("humanoid-walk", "walk_s", "humanoid-walk-open-loop"),
)


def current_study_name(name: str, problem_keys: Any = ()) -> str:
    """The study a run folder (or a checkpoint's record) naming ``name`` with these
    ``[problem]`` keys is now (:data:`RENAMED_STUDIES`); ``name`` when it was not renamed."""
    keys = set(problem_keys) if isinstance(problem_keys, dict | list | set | tuple) else set()
    for old, key, new in RENAMED_STUDIES:
        if name == old and (key is None or key in keys):
            return new
    return name


#: keys a study gained after run folders were written whose default changes (or may change)
#: what such a run does: absent from a saved config, they read as these values (what those
#: runs did). 33: humanoid-balance's stance (sim/stance.py; those runs stood in the spec pose;
#: runs before its lean stood upright, which the lean's default 0 also gives; runs before
#: problem.validate_every exported the best single centre score, which 0 gives).
ADDED_KEYS: dict[str, dict[str, dict[str, Any]]] = {
    "humanoid-balance": {"problem": {"stance_width_rad": 0.0, "stance_stagger_rad": 0.0,
                                     "stance_crouch_rad": 0.0, "stance_lean_rad": 0.0,
                                     "validate_every": 0, "validate_episodes": 32}},
    # 34: the walk's command kinds, mirror-symmetric controllers and capture steps, which a
    # robot's defaults (Study.robot_defaults) now set (a saved dm-humanoid or NAO run reruns
    # as it ran)
    "humanoid-walk": {"problem": {"symmetric": False,
                                  "command_weights": [0.3, 0.15, 0.15, 0.3, 0.1],
                                  "capture_gain": 0.0}},
}


def as_now(raw: dict[str, Any]) -> dict[str, Any]:
    """A raw run config as its study reads it now: its ``study`` under the name it has now
    (:func:`current_study_name` of its ``[problem]`` keys), and the keys added since
    (:data:`ADDED_KEYS`) that it lacks set to what it ran with; ``raw`` itself when it names
    no study or neither applies."""
    name = raw.get("study")
    if not isinstance(name, str):
        return raw
    problem = raw.get("problem")
    now = current_study_name(name, problem if isinstance(problem, dict) else ())
    out = raw if now == name else {**raw, "study": now}
    for section, keys in ADDED_KEYS.get(now, {}).items():
        table = out.get(section)
        if isinstance(table, dict) and any(k not in table for k in keys):
            out = {**out, section: {**keys, **table}}
    return out


def saved_as_now(study: ConfiguredStudy, raw: dict[str, Any]) -> dict[str, Any]:
    """A ``--config`` file that is a saved run config of ``study`` (it names the study, and a
    section that lacks keys added since (:data:`ADDED_KEYS`) holds every other key of that
    section, as the run loop writes them) with those keys as its runs had them, so it reruns
    the same experiment; any other file (a hand-written partial one: a key it lacks takes the
    default) as it is."""
    name = raw.get("study")
    problem = raw.get("problem")
    if not isinstance(name, str) or current_study_name(
            name, problem if isinstance(problem, dict) else ()) != study.name:
        return raw
    classes = {"run": RunSection, "problem": study.problem_config}
    for section, keys in ADDED_KEYS.get(study.name, {}).items():
        table = raw.get(section)
        older = {f.name for f in dataclasses.fields(classes[section])} - set(keys)
        if isinstance(table, dict) and not older <= set(table):
            return raw  # a partial (hand-written) file: its missing keys take the defaults
    return as_now(raw)


def config_from_run_dir(run_dir: Path) -> tuple[str, dict[str, Any]]:
    """Study name and raw config saved in a run folder (``config.toml``), as the study reads it
    now (:func:`as_now`: a study renamed since under its name now, keys added since as the run
    had them)."""
    path = Path(run_dir) / "config.toml"
    if not path.exists():
        raise InputError(f"{run_dir}: not a run folder (no config.toml)")
    raw = load_toml(path)
    if not isinstance(raw.get("study"), str):
        raise FileFormatError(path, None, "expected a top-level 'study' key naming the study")
    raw = as_now(raw)
    return raw["study"], raw


def configured_robot(raw: dict[str, Any], key: str = "robot") -> Any:
    """A raw run config's ``problem.robot`` (or ``problem.<key>``) as written (``""``, the
    study's own robot, when there is none); the caller checks what it may load.
    :func:`resolve_config` reads it from the user's layers only (file, values, ``--set``): a
    study default or preset that set it would not choose ``robot_defaults`` (none does)."""
    problem = raw.get("problem")
    return problem.get(key, "") if isinstance(problem, dict) else ""


def study_of_run(path: str | Path) -> str | None:
    """The study a run folder's ``config.toml`` names; None where ``path`` is no folder with a
    ``config.toml`` (a bad one is one :class:`InputError` line)."""
    p = Path(path)
    if not (p.is_dir() and (p / "config.toml").is_file()):
        return None
    return config_from_run_dir(p)[0]


def run_of_study(path: str | Path, study: str, option: str = "RUN",
                 subfolder: str | None = None) -> Path:
    """The run folder ``path`` if its ``config.toml`` names ``study`` (``path`` may also be
    its ``subfolder``); another study's run, or no run, is one :class:`InputError` line."""
    p = Path(path)
    if subfolder and p.name == subfolder and not (p / "config.toml").exists() \
            and (p.parent / "config.toml").exists():
        p = p.parent
    if not p.is_dir():
        raise InputError(f"{option} {path}: expected a {study} run folder, found no folder")
    name, _ = config_from_run_dir(p)
    if name != study:
        raise InputError(f"{option} {path}: a {name} run, expected a {study} run folder")
    return p

