"""Config keys a study moved (``Study.moved_keys``: ``{"problem.method": "algorithm.method"}``).

A config written with a key's old place (a TOML file, ``--set``, a run folder's
``config.toml`` on resume, a checkpoint's recorded config) keeps working: the key is read at
its new place, with one note naming both. An old key whose new place the chosen method has
no such setting (``algorithm.X`` of another ``algorithm.name``) is dropped with a note. The
old and the new key both given in one source is one :class:`~evomotion.errors.InputError`.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Mapping
from typing import Any

from evomotion.errors import InputError

_LOG = logging.getLogger(__name__)


def move_sources(sources: list[dict[str, Any]], moved: Mapping[str, str],
                 sections: Mapping[str, type] | None, algorithm: str) -> list[dict[str, Any]]:
    """Each config source (sections of keys) with the old keys of ``moved`` at their new
    place (:func:`move_keys`), and one note on stderr naming them all (the loggers' last
    resort).
    ``sections``: the config's dataclass of each section for method ``algorithm``; ``None``
    (an unknown method, whose own error follows): the sources unchanged."""
    if not moved or sections is None:
        return sources
    out, notes = [], []
    for raw in sources:
        raw, said = move_keys(raw, moved, sections, algorithm)
        out.append(raw)
        notes += said
    if notes:  # one line for all of them (a resumed old run folder moves nine at once)
        _LOG.warning("note: " + "; ".join(dict.fromkeys(notes)))
    return out


def move_keys(raw: Mapping[str, Any], moved: Mapping[str, str], sections: Mapping[str, type],
              algorithm: str) -> tuple[dict[str, Any], list[str]]:
    """``raw`` (sections of keys) with every old key of ``moved`` at its new place, and one
    note per moved key; ``sections``: the dataclass of each section (of method
    ``algorithm``), which says where a key exists. ``raw`` itself is not changed. A note is
    ``"<old> is the old name of <new>"``."""

    def has(key: str) -> bool:
        section, _, name = key.partition(".")
        cls = sections.get(section)
        return cls is not None and name in {f.name for f in dataclasses.fields(cls)}

    out = {k: dict(v) if isinstance(v, dict) else v for k, v in raw.items()}
    notes: list[str] = []
    for old, new in moved.items():
        old_sec, _, old_key = old.partition(".")
        new_sec, _, new_key = new.partition(".")
        src = out.get(old_sec)
        if not isinstance(src, dict) or old_key not in src:
            continue
        if not has(new):
            del src[old_key]
            notes.append(f"{old} is the old name of {new}, a setting that "
                         f"algorithm.name = {algorithm!r} does not have (ignored)")
            continue
        dst = out.setdefault(new_sec, {})
        if not isinstance(dst, dict):
            continue  # the section's own error follows ("'algorithm' must be a table")
        if new_key in dst:
            raise InputError(f"{old} and {new}: the same setting under its old and its new "
                             f"name; give only {new}")
        dst[new_key] = src.pop(old_key)
        notes.append(f"{old} is the old name of {new}")
    return out, notes


def moved_record(recorded: Mapping[str, Any], moved: Mapping[str, str],
                 now: Mapping[str, Any]) -> dict[str, Any]:
    """A checkpoint's recorded config (``{"problem.method": ...}``, flat) with the moved keys
    at their new place, as :func:`move_keys` reads a config: a key whose new place ``now``
    (the run's config now) lacks is dropped (the chosen method has no such setting)."""
    out = dict(recorded)
    for old, new in moved.items():
        if old in out:
            value = out.pop(old)
            if new in now and new not in out:
                out[new] = value
    return out
