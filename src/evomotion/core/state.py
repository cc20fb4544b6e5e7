"""Checkpointable state: dataclasses of numpy arrays and scalars <-> npz arrays + JSON.

No pickle anywhere: array fields go to an ``.npz`` file, everything else (ints, floats,
strings, bools, ``None``, lists and dicts of those) to JSON. Nested state dataclasses are
flattened with dotted keys. A ``numpy.random.Generator`` is stored as its bit generator's
state dict.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any

import numpy as np


def state_to_arrays(state: Any, prefix: str = "") -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Split a state dataclass into (arrays, json-able meta)."""
    arrays: dict[str, np.ndarray] = {}
    meta: dict[str, Any] = {}
    for f in dataclasses.fields(state):
        v = getattr(state, f.name)
        key = prefix + f.name
        if dataclasses.is_dataclass(v):
            a, m = state_to_arrays(v, key + ".")
            arrays.update(a)
            meta.update(m)
        elif isinstance(v, np.ndarray):
            arrays[key] = v
        elif isinstance(v, np.generic):
            meta[key] = v.item()
        else:
            meta[key] = v
    return arrays, meta


def state_from_arrays(cls: type, arrays: dict[str, np.ndarray], meta: dict[str, Any],
                      prefix: str = "") -> Any:
    """Inverse of :func:`state_to_arrays` for the dataclass type ``cls``."""
    kwargs = {}
    hints = {f.name: f for f in dataclasses.fields(cls)}
    declared = _declared_types(cls)
    for name, f in hints.items():
        key = prefix + name
        ftype = f.type if isinstance(f.type, type) else None
        if key in arrays:
            kwargs[name] = _checked(key, np.array(arrays[key]), declared.get(name))
        elif key in meta:
            kwargs[name] = _checked(key, meta[key], declared.get(name))
        elif ftype is not None and dataclasses.is_dataclass(ftype):
            kwargs[name] = state_from_arrays(ftype, arrays, meta, key + ".")
        else:
            sub = _nested_type(cls, name)
            if sub is None:
                raise KeyError(f"checkpoint lacks state field {key!r}")
            kwargs[name] = state_from_arrays(sub, arrays, meta, key + ".")
    return cls(**kwargs)


#: the declared types checked, and what the error calls them (a JSON number may stand for
#: an int or a float field: a float field may hold an int, an int one a whole float)
_NAMES = {int: "a number", float: "a number", bool: "true or false", str: "a string",
          np.ndarray: "a numeric array"}


def _declared_types(cls: type) -> dict[str, tuple[type, ...]]:
    """``{field: the types its value may have}`` for the fields declared as ``int``,
    ``float``, ``bool``, ``str`` or ``np.ndarray``, alone or ``| None``; other annotations
    (``Any``, containers, nested states) are not checked."""
    import types
    import typing

    try:
        hints = _type_hints(cls)
    except Exception:  # an annotation this module cannot resolve: nothing checked
        return {}
    out = {}
    for name, t in hints.items():
        parts = typing.get_args(t) if isinstance(t, types.UnionType) or \
            typing.get_origin(t) is typing.Union else (t,)
        known = tuple(p for p in parts if p in _NAMES or p is type(None))
        if known and len(known) == len(parts):
            out[name] = known
    return out


def checked_fields(cls: type, values: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """``values`` (field name -> value read from a checkpoint) checked against the fields'
    declared types as :func:`state_from_arrays` checks them, for a driver that builds its
    state's top level itself."""
    declared = _declared_types(cls)
    return {k: _checked(prefix + k, v, declared.get(k)) for k, v in values.items()}


def _checked(key: str, value: Any, allowed: tuple[type, ...] | None) -> Any:
    """``value`` if it may be the checkpointed value of a field declared ``allowed``, else a
    ``TypeError`` naming the field (resume then refuses the checkpoint in one line)."""
    if allowed is None:
        return value
    numeric = isinstance(value, np.ndarray) and value.dtype.kind in "biuf"
    number = isinstance(value, int | float) and not isinstance(value, bool)
    for t in allowed:
        if t is type(None) and value is None:
            return value
        # an array field that held a numpy scalar was written as a JSON number, a number
        # field that held a 0-d array as an array: both are read back as they were written
        if t is np.ndarray and (numeric or number):
            return value
        if t in (int, float) and (number or numeric and value.ndim == 0):
            return value
        if t is bool and (isinstance(value, bool) or numeric and value.ndim == 0):
            return value
        if t is str and isinstance(value, str):
            return value
    expected = " or ".join("null" if t is type(None) else _NAMES[t] for t in allowed)
    shown = f"an array of {value.dtype}" if isinstance(value, np.ndarray) else repr(value)[:40]
    raise TypeError(f"state field {key!r}: expected {expected}, got {shown}")


def _nested_type(cls: type, name: str) -> type | None:
    t = _type_hints(cls).get(name)
    return t if isinstance(t, type) and dataclasses.is_dataclass(t) else None


@functools.cache
def _type_hints(cls: type) -> dict[str, Any]:
    """``typing.get_type_hints(cls)``, resolved once per state class."""
    import typing

    return typing.get_type_hints(cls)


def rng_state(rng: np.random.Generator) -> dict[str, Any]:
    return dict(rng.bit_generator.state)


def rng_from_state(state: dict[str, Any]) -> np.random.Generator:
    bitgen = getattr(np.random, state["bit_generator"])()
    bitgen.state = state
    return np.random.Generator(bitgen)


def replaced(state: Any, **changes: Any) -> Any:
    """A shallow copy of the state dataclass ``state`` with ``changes`` (what
    ``dataclasses.replace`` does for a plain, non-frozen state without ``__post_init__``, at
    a fraction of its cost: the cellular GA replaces its state once per wave)."""
    cls = type(state)
    if not hasattr(state, "__dict__") or hasattr(cls, "__post_init__") or \
            cls.__dataclass_params__.frozen:
        return dataclasses.replace(state, **changes)
    new = object.__new__(cls)
    new.__dict__.update(state.__dict__)
    new.__dict__.update(changes)
    return new
