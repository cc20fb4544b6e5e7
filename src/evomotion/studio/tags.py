"""A run's tags (issue 35: "name/tag a run"), as W&B and TensorBoard users label runs: short
words kept in the run folder's ``tags.txt`` (one per line), shown beside the run's name in the
runs list, filterable there, editable on the run page and offered as a "group by" key on the
comparison page. The studio writes only this file, and only on the user's request.

Reading is bounded and never blocks (a FIFO or a huge ``tags.txt`` reads as no tags); what
the user types is checked (one :class:`~evomotion.errors.InputError` line naming the tag).
"""

from __future__ import annotations

import re
from pathlib import Path

from evomotion.errors import InputError
from evomotion.studio.readers import one_line, read_range

NAME = "tags.txt"
#: a tag: 1-32 letters, digits, '.', '_', '+', '-' (a word, a version, "lr=0.1" is not one)
TAG = re.compile(r"[A-Za-z0-9][A-Za-z0-9._+-]{0,31}")
MAX_TAGS = 16
MAX_BYTES = 4096


def parse_tags(text: object) -> tuple[str, ...]:
    """The tags in ``text`` (separated by commas or white space; duplicates dropped, order
    kept), or one :class:`InputError` line naming the first bad one."""
    if not isinstance(text, str):
        raise InputError("tags: expected text (tags separated by commas or spaces)")
    return check_tags([t for t in re.split(r"[,\s]+", text) if t])


def check_tags(found: object) -> tuple[str, ...]:
    """A sequence of tags checked one by one (duplicates dropped, order kept), or one
    :class:`InputError` line naming the first bad one."""
    if not isinstance(found, list | tuple):
        raise InputError("tags: expected a list of tags")
    for t in found:
        if not isinstance(t, str) or not TAG.fullmatch(t):
            raise InputError(f"tag {one_line(repr(t), 40)}: expected 1-32 letters, digits, "
                             "'.', '_', '+' or '-', starting with a letter or digit")
    tags = tuple(dict.fromkeys(found))
    if len(tags) > MAX_TAGS:
        raise InputError(f"tags: at most {MAX_TAGS} per run, got {len(tags)}")
    return tags


def read_tags(run_dir: Path) -> tuple[str, ...]:
    """The run's tags; none for a missing, unreadable, oversized or damaged ``tags.txt``
    (the lines that are tags are kept)."""
    raw, size = read_range(Path(run_dir) / NAME, 0, MAX_BYTES)
    if size > MAX_BYTES:
        return ()
    lines = raw.decode("utf-8", "replace").split()
    return tuple(dict.fromkeys(t for t in lines if TAG.fullmatch(t)))[:MAX_TAGS]


def write_tags(run_dir: Path, tags: tuple[str, ...] | list[str]) -> None:
    """``tags.txt`` replaced atomically (removed for no tags); the tags checked first."""
    from evomotion.outfile import atomic_write_text

    tags = check_tags(tags)
    path = Path(run_dir) / NAME
    if tags:
        atomic_write_text(path, "".join(f"{t}\n" for t in tags))
    else:
        path.unlink(missing_ok=True)


def editor(ui, run_dir: Path) -> None:
    """The run page's tags: an input and a save button (a bad tag: one line under it)."""
    with ui.row().classes("items-center"):
        field = ui.input("tags", value=" ".join(read_tags(run_dir)),
                         placeholder="baseline, lr-sweep").classes("w-96 run-tags")
        message = ui.label().classes("text-xs run-tags-message")

        def save() -> None:
            try:
                write_tags(run_dir, parse_tags(field.value or ""))
            except (InputError, OSError) as e:  # WriteError is an InputError
                message.set_text(f"error: {one_line(e)}")
                message.classes(replace="text-xs text-red-700 run-tags-message")
                return
            field.set_value(" ".join(read_tags(run_dir)))
            message.set_text("saved")
            message.classes(replace="text-xs text-green-700 run-tags-message")

        ui.button("save tags", icon="sell", on_click=save).classes("tags-button")
