"""Repertoire indexes written before ``stepper`` existed (:mod:`evomotion.sim.repertoire`):
they carried a NAO flag ``is_nao`` (true: the NAO's closed-form step), and the oldest named
their robot only (all were the NAO's closed-form steps). Read here, never written."""

from __future__ import annotations

OLD_FLAG = "is_nao"


def old_flag_problem(index: dict) -> str | None:
    """What is wrong with an old index's flag (``None``: nothing)."""
    if OLD_FLAG in index and not isinstance(index[OLD_FLAG], bool):
        return f"expected '{OLD_FLAG}' true or false"
    return None


def old_stepper(index: dict) -> str:
    """The step model of an index without ``stepper``: ``"closed_form"`` or ``"numerical"``."""
    flag = index.get(OLD_FLAG)
    closed = flag if isinstance(flag, bool) else index.get("robot", "nao") == "nao"
    return "closed_form" if closed else "numerical"
