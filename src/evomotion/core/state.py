"""Checkpointable state: dataclasses of numpy arrays and scalars <-> npz arrays + JSON.

No pickle anywhere: array fields go to an ``.npz`` file, everything else (ints, floats,
strings, bools, ``None``, lists and dicts of those) to JSON. Nested state dataclasses are
flattened with dotted keys. A ``numpy.random.Generator`` is stored as its bit generator's
state dict.
"""

from __future__ import annotations

import dataclasses
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
    for name, f in hints.items():
        key = prefix + name
        ftype = f.type if isinstance(f.type, type) else None
        if key in arrays:
            kwargs[name] = np.array(arrays[key])
        elif key in meta:
            kwargs[name] = meta[key]
        elif ftype is not None and dataclasses.is_dataclass(ftype):
            kwargs[name] = state_from_arrays(ftype, arrays, meta, key + ".")
        else:
            sub = _nested_type(cls, name)
            if sub is None:
                raise KeyError(f"checkpoint lacks state field {key!r}")
            kwargs[name] = state_from_arrays(sub, arrays, meta, key + ".")
    return cls(**kwargs)


def _nested_type(cls: type, name: str) -> type | None:
    import typing

    hints = typing.get_type_hints(cls)
    t = hints.get(name)
    return t if isinstance(t, type) and dataclasses.is_dataclass(t) else None


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
