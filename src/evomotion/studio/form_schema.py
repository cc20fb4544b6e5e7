"""What the new-run form shows of a config key: its value as a user writes it, its
documentation, its choices, whether it is a common key, and every error of a filled form.

- **Values**: TOML literals as ``--set`` takes them (a dict is an inline table
  ``{eta = 15.0}``, not Python's ``{'eta': 15.0}``); a float whose shortest text is long shows
  6 significant digits (``0.785398``), and the field counts as changed only when its text is
  edited (the exact value is in the field's hint);
- **Documentation**: the comment after the field in its dataclass (units and ranges are
  written there: ``# mujoco.rollout threads, [0, 1024]; 0 = all cores``) or the ``#:`` lines
  above it;
- **Choices**: the registries the key is checked against (evaluators, loggers, the GA's
  operators, bundled robots; a robot may also be a spec file, so that select takes free text);
- **Common keys**: the run's budget and seed, the population size, and whatever the study's
  presets set (what the paper varies); the rest is "advanced".
"""

from __future__ import annotations

import inspect
import json
import re
from functools import cache
from typing import Any

from evomotion.errors import InputError

#: keys shown in the form's first group whatever the study
COMMON = ("run.seed", "run.generations", "run.max_evaluations", "run.wall_seconds",
          "run.target", "run.evaluator", "run.workers", "algorithm.pop_size")
_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")
_COMMENT = re.compile(r"^\s*(\w+)\s*:[^#]*?(?:#\s*(.*))?$")


def toml_text(v: Any) -> str:
    """``v`` as a TOML literal (``--set`` parses it back to ``v``)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if v is None:
        return "none"
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, dict):
        items = (f"{k if _BARE_KEY.match(str(k)) else json.dumps(str(k))} = {toml_text(x)}"
                 for k, x in v.items())
        return "{" + ", ".join(items) + "}"
    if isinstance(v, tuple | list):
        return "[" + ", ".join(toml_text(x) for x in v) + "]"
    return repr(v)


def shown_text(kind: str, v: Any) -> str:
    """What the field shows: a bare string for a ``str`` key, 6 significant digits for a float
    whose shortest text is longer than 10 characters, else the TOML literal."""
    if kind == "str" and isinstance(v, str):
        return v
    if kind == "float" and isinstance(v, float) and len(repr(v)) > 10:
        return f"{v:.6g}"
    return toml_text(v)


@cache
def field_docs(cls: type) -> dict[str, str]:
    """The comment of each field of dataclass ``cls`` (and of its bases): the text after
    ``#`` on its line, or the ``#:`` lines just above it."""
    docs: dict[str, str] = {}
    for klass in reversed(cls.__mro__[:-1]):
        try:
            lines = inspect.getsource(klass).splitlines()
        except (OSError, TypeError):
            continue
        above: list[str] = []
        for line in lines:
            s = line.strip()
            if s.startswith("#:"):
                above.append(s[2:].strip())
                continue
            m = _COMMENT.match(line) if not s.startswith(("def ", "@", "#")) else None
            if m and line.startswith("    ") and not line.startswith("     "):
                text = " ".join([*above, m.group(2) or ""]).strip()
                if text:
                    docs[m.group(1)] = text
            above = []
    return docs


def choices(key: str) -> tuple[list[str], bool] | None:
    """``(options, free)`` of a key checked against a registry (``free``: other values are
    allowed too, e.g. a robot spec file), or None."""
    name = key.split(".", 1)[1]
    if key == "run.evaluator":
        from evomotion.run.evaluators import EVALUATORS

        return sorted(EVALUATORS), False
    if key == "problem.robot":
        from evomotion.sim.robots import bundled_robots

        return ["", *bundled_robots()], True
    if key == "problem.env":  # gym: the registered MuJoCo v5 tasks (with the gym extra)
        try:
            from gymnasium.envs.registration import registry
        except ImportError:
            return None
        return sorted(k for k, e in registry.items() if k.endswith("-v5")
                      and "mujoco" in str(e.entry_point)), True
    registries = {"crossover": "crossover.CROSSOVERS", "mutation": "mutation.MUTATIONS",
                  "selection": "selection.SELECTIONS", "replacement": "replacement.REPLACEMENTS"}
    if key.startswith("algorithm.") and name in registries:
        import importlib

        module, attr = registries[name].split(".")
        reg = getattr(importlib.import_module(f"evomotion.core.operators.{module}"), attr)
        return sorted(reg), False
    return None


def common_keys(study: Any) -> set[str]:
    """:data:`COMMON`, the key that picks the robot's own defaults (``problem.robot``; gym's
    ``problem.env``: ``Study.defaults_key``) where it has any, and every key a preset of
    ``study`` sets (on any robot or environment, ``Study.robot_presets``)."""
    keys = set(COMMON)
    if getattr(study, "robot_defaults", None) or getattr(study, "robot_presets", None):
        keys.add(f"problem.{getattr(study, 'defaults_key', 'robot')}")
    keyed = [layer for by_robot in getattr(study, "robot_presets", {}).values()
             for layer in by_robot.values()]
    for preset in [*getattr(study, "presets", {}).values(), *keyed]:
        for sec, table in (preset or {}).items():
            if isinstance(table, dict):
                keys.update(f"{sec}.{k}" for k in table if k != "name")
    return keys


def field_of_error(message: str, keys: list[str]) -> str | None:
    """The form key a one-line error names (longest match), if any."""
    hits = [k for k in keys if k in message]
    return max(hits, key=len) if hits else None


def all_errors(check: Any, sets: list[str], keys: list[str]) -> dict[str | None, str]:
    """Every error of a form at once: ``check(sets)`` raises the resolver's first one-line
    :class:`InputError`; each ``--set`` is then checked on its own (with the algorithm's),
    and an error no single key causes is kept under None (or the key it names)."""
    try:
        check(sets)
        return {}
    except InputError as e:
        first = str(e)
    algorithm = [s for s in sets if s.startswith("algorithm.name=")]
    errors: dict[str | None, str] = {}
    for item in sets:
        if item in algorithm:
            continue
        try:
            check([*algorithm, item])
        except InputError as e:
            errors[item.split("=", 1)[0]] = str(e)
    if not errors:
        errors[field_of_error(first, keys)] = first
    return errors
