"""Plain-dict registries with helpful errors for unknown names."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

from evomotion.errors import InputError

T = TypeVar("T")


class UnknownNameError(InputError, KeyError):
    """Raised for an unknown registry entry; ``str()`` is a one-line user-facing message."""

    def __str__(self) -> str:
        return str(self.args[0])


def lookup(registry: dict[str, T], kind: str, name: str) -> T:
    """``registry[name]`` or an error such as "unknown crossover 'blx'; available: ..."."""
    try:
        return registry[name]
    except KeyError:
        avail = ", ".join(sorted(registry))
        raise UnknownNameError(f"unknown {kind} {name!r}; available: {avail}") from None


def register(registry: dict[str, Any], name: str) -> Callable[[T], T]:
    """Decorator adding a function to ``registry`` under ``name``."""

    def deco(fn: T) -> T:
        if name in registry:
            raise ValueError(f"duplicate registry name {name!r}")
        registry[name] = fn
        return fn

    return deco
