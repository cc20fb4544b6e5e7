"""One-line checks of config values, shared by the config dataclasses' ``validate()``.

Every message names the key and what was expected (``algorithm.sigma0: expected > 0, got
-1.0``), so that the CLI can print it as one line (:class:`~evomotion.errors.InputError`).

Non-finite floats: a ``float`` field of a config dataclass must be finite unless the field
documents a meaning for ``inf`` with :func:`inf_ok` (its metadata key :data:`ALLOW_INF`
holds that meaning, e.g. ``"no time limit"``); ``nan`` never means anything and is always
refused. :func:`check_fields` applies this (and the integer rules) to every field of a
dataclass, so a config built directly in Python is held to the same rules as one read from
TOML or ``--set`` (where :func:`evomotion.run.config.build_section` applies them first).
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from typing import Any

from evomotion.errors import InputError

#: dataclass field metadata key: the documented meaning of ``inf`` for that float field
ALLOW_INF = "allow_inf"
#: integers are 64-bit signed (TOML's range; numpy and the checkpoints need no more)
INT_LIMIT = 2**63
#: the largest population any optimizer accepts (the memory check usually refuses sooner)
MAX_POP_SIZE = 10**12


def inf_ok(default: float, meaning: str) -> Any:
    """A float dataclass field whose ``inf`` means ``meaning`` (``nan`` is still refused)."""
    return dataclasses.field(default=default, metadata={ALLOW_INF: meaning})


def _fmt(v: float) -> str:
    return repr(v) if isinstance(v, float) else str(v)


def _range_text(lo: float | None, hi: float | None, lo_open: bool, hi_open: bool) -> str:
    if lo is not None and hi is not None:
        left, right = "(" if lo_open else "[", ")" if hi_open else "]"
        return f"a value in {left}{_fmt(lo)}, {_fmt(hi)}{right}"
    if lo is not None:
        return f"{'>' if lo_open else '>='} {_fmt(lo)}"
    if hi is not None:
        return f"{'<' if hi_open else '<='} {_fmt(hi)}"
    return "a number"


def check_number(key: str, value: Any, *, lo: float | None = None, hi: float | None = None,
                 lo_open: bool = False, hi_open: bool = False, integer: bool = False,
                 allow_inf: bool = False) -> None:
    """Raise a one-line :class:`InputError` unless ``value`` is a number in the range.

    ``integer``: an ``int`` (never a ``bool``) within 64 bits; otherwise an ``int`` or a
    finite ``float`` (``allow_inf``: ``±inf`` pass the finiteness test, not the range)."""
    what = "an integer" if integer else "a number"
    if isinstance(value, bool) or not isinstance(value, int | float) or (
            integer and not isinstance(value, int)):
        raise InputError(f"{key}: expected {what}, got {type(value).__name__} {value!r}")
    if isinstance(value, int) and not -INT_LIMIT <= value < INT_LIMIT:
        raise InputError(f"{key}: expected {what} of at most 64 bits, got {value}")
    if isinstance(value, float) and math.isnan(value):
        raise InputError(f"{key}: expected a finite number, got nan")
    if isinstance(value, float) and math.isinf(value) and not allow_inf:
        raise InputError(f"{key}: expected a finite number, got {value}")
    bad = ((lo is not None and (value <= lo if lo_open else value < lo))
           or (hi is not None and (value >= hi if hi_open else value > hi)))
    if bad:
        raise InputError(f"{key}: expected {_range_text(lo, hi, lo_open, hi_open)}, "
                         f"got {_fmt(value)}")


def check_choice(key: str, value: Any, choices: typing.Iterable[Any]) -> None:
    """Raise unless ``value`` is one of ``choices``."""
    choices = tuple(choices)
    if value not in choices:
        raise InputError(f"{key}: expected one of {', '.join(map(str, choices))}, "
                         f"got {value!r}")


def check_text(key: str, value: Any, *, empty: bool = True) -> None:
    """Raise unless ``value`` is a string without NUL characters (``empty``: may be "")."""
    if not isinstance(value, str):
        raise InputError(f"{key}: expected a string, got {type(value).__name__} {value!r}")
    if "\x00" in value:
        raise InputError(f"{key}: expected text without NUL characters, got {value!r}")
    if not empty and not value.strip():
        raise InputError(f"{key}: expected a non-empty string, got {value!r}")


def _scalar_kind(tp: Any) -> type | None:
    """``int``, ``float`` or ``str`` for a (possibly optional) scalar annotation."""
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        tp = args[0] if len(args) == 1 else None
    return tp if tp in (int, float, str) else None


def check_fields(obj: Any, section: str) -> None:
    """Apply the generic rules to every field of dataclass ``obj``: floats finite (unless
    :func:`inf_ok`), ints not bools and within 64 bits, strings without NUL characters."""
    hints = typing.get_type_hints(type(obj))
    for f in dataclasses.fields(obj):
        kind, value = _scalar_kind(hints.get(f.name)), getattr(obj, f.name)
        if kind is None or value is None:
            continue
        key = f"{section}.{f.name}"
        if kind is str:
            check_text(key, value)
        elif kind is int:
            check_number(key, value, integer=True)
        else:
            check_number(key, value, allow_inf=ALLOW_INF in f.metadata)
