"""Safe reading of user files: bytes with a size limit, strict UTF-8, one-line errors.

Every reader of a user file goes through :func:`read_file_bytes` (missing file, directory,
unreadable, too large) and :func:`decode_utf8` / :func:`read_text_lines` (undecodable bytes
reported as ``FILE:LINE: expected UTF-8 text (byte 0xNN at column C)``), so that a hostile
file can only ever raise :class:`~evomotion.errors.FileFormatError`.
"""

from __future__ import annotations

import json
import math
import os
import re
import stat
from pathlib import Path
from typing import Any

from evomotion.errors import FileFormatError

#: Default largest file a reader accepts (bytes); readers pass their own where it matters.
MAX_FILE_BYTES = 64 * 1024 * 1024


def _size_text(n: int) -> str:
    return f"{n / 2**20:g} MiB" if n >= 2**20 else f"{n} bytes"


def read_file_bytes(path: str | Path, what: str = "file",
                    max_bytes: int = MAX_FILE_BYTES) -> bytes:
    """The bytes of ``path``, or :class:`FileFormatError` (missing, not a regular file,
    unreadable, larger than ``max_bytes``). Nothing but a regular file is opened for reading
    (a FIFO would block, ``/dev/zero`` never ends), and the size is checked before anything
    is read."""
    path = Path(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise FileFormatError(path, None, f"expected an existing {what}") from None
    except (OSError, ValueError) as e:
        raise FileFormatError(path, None, f"expected a readable {what} ({_reason(e)})") from None
    _check_regular(path, st.st_mode, what)
    if st.st_size > max_bytes:
        raise FileFormatError(path, None, f"expected a {what} of at most "
                                          f"{_size_text(max_bytes)}, got {_size_text(st.st_size)}")
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)  # swapped for a FIFO: no block
    except (OSError, ValueError) as e:
        raise FileFormatError(path, None, f"expected a readable {what} ({_reason(e)})") from None
    try:
        _check_regular(path, os.fstat(fd).st_mode, what)
        with os.fdopen(fd, "rb") as f:
            fd = -1
            data = f.read(max_bytes + 1)  # a growing file cannot exceed the limit
    except OSError as e:
        raise FileFormatError(path, None, f"expected a readable {what} ({_reason(e)})") from None
    finally:
        if fd >= 0:
            os.close(fd)
    if len(data) > max_bytes:
        raise FileFormatError(path, None, f"expected a {what} of at most "
                                          f"{_size_text(max_bytes)}")
    return data


def _check_regular(path: Path, mode: int, what: str) -> None:
    if stat.S_ISDIR(mode):
        raise FileFormatError(path, None, f"expected a {what}, got a directory")
    kind = kind_of(mode)
    if kind is not None:
        raise FileFormatError(path, None, f"expected a regular {what}, got {kind}")


_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"))


def kind_of(mode: int) -> str | None:
    """``"a FIFO"`` etc. for anything but a regular file; ``None`` for a regular file."""
    for test, name in _KINDS:
        if test(mode):
            return name
    return None if stat.S_ISREG(mode) else "not a regular file"


def _reason(e: BaseException) -> str:
    return (getattr(e, "strerror", None) or str(e) or type(e).__name__).replace("\n", " ")


def utf8_error(path: str | Path, data: bytes, exc: UnicodeDecodeError) -> FileFormatError:
    """The one-line error for the first undecodable byte of ``data``."""
    pos = exc.start
    line = data.count(b"\n", 0, pos) + 1
    column = pos - (data.rfind(b"\n", 0, pos) + 1) + 1
    return FileFormatError(path, line, f"expected UTF-8 text (byte 0x{data[pos]:02x} at "
                                       f"column {column})")


def decode_utf8(data: bytes, path: str | Path, bom: bool = True) -> str:
    """``data`` as text (strict UTF-8 without NUL bytes; a leading BOM is dropped when
    ``bom``)."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise utf8_error(path, data, e) from None
    if "\0" in text:  # valid UTF-8, but no text format has NULs (UTF-16 without a BOM has)
        pos = data.index(b"\0")
        raise utf8_error(path, data, UnicodeDecodeError("utf-8", data, pos, pos + 1, "NUL"))
    if bom and text.startswith("\ufeff"):
        text = text[1:]
    return text


def split_lines(text: str) -> list[str]:
    """Lines split at ``\\n`` only (``\\r\\n`` is fine), so that line numbers are those an
    editor shows; a final newline does not add an empty line."""
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    return [ln[:-1] if ln.endswith("\r") else ln for ln in lines]


def read_text_lines(path: str | Path, what: str = "file",
                    max_bytes: int = MAX_FILE_BYTES) -> list[str]:
    """The lines of a UTF-8 text file (see :func:`split_lines`); every failure is a
    :class:`FileFormatError` naming the file (and the line of a bad byte)."""
    return split_lines(decode_utf8(read_file_bytes(path, what, max_bytes), path))


#: Default deepest nesting of a JSON document a reader accepts (this program writes <= 4)
MAX_JSON_DEPTH = 32
#: a string (linear: an unterminated one runs to the end of the text) or a bracket
_JSON_TOKENS = re.compile(r'"[^"\\]*(?:\\.[^"\\]*)*"?|[\[\]{}]')


def json_depth(text: str, limit: int) -> int:
    """The nesting depth of the JSON ``text`` (strings skipped), counted only up to
    ``limit + 1`` (the scan stops there: a hostile document costs no more than that)."""
    depth = deepest = 0
    for m in _JSON_TOKENS.finditer(text):
        c = m.group()
        if c in "[{":
            depth += 1
            if depth > deepest:
                deepest = depth
                if deepest > limit:
                    break
        elif c in "]}":
            depth -= 1
    return deepest


def loads_json(text: str, path: str | Path, max_depth: int = MAX_JSON_DEPTH,
               finite: bool = True) -> Any:
    """The JSON document ``text`` (from ``path``); nested deeper than ``max_depth``, not
    JSON, or (when ``finite``) holding ``NaN``/``Infinity`` or a number too large for a float
    is one :class:`FileFormatError` naming the file and line."""
    if json_depth(text, max_depth) > max_depth:
        raise FileFormatError(path, None, f"expected JSON nested at most {max_depth} deep")

    def constant(name: str) -> float:
        if finite:
            raise _NonFiniteError(name)
        return float(name)

    def number(s: str) -> float:
        v = float(s)
        if finite and not math.isfinite(v):
            raise _NonFiniteError(s)
        return v

    try:
        return json.loads(text, parse_constant=constant, parse_float=number)
    except _NonFiniteError as e:
        raise FileFormatError(path, None, f"expected finite numbers, got {str(e)[:40]}"
                              ) from None
    except json.JSONDecodeError as e:
        raise FileFormatError(path, e.lineno, f"column {e.colno}: invalid JSON: {e.msg}"
                              ) from None
    except (RecursionError, ValueError) as e:  # ValueError: an integer of > 4300 digits
        raise FileFormatError(path, None, f"invalid JSON ({type(e).__name__})") from None


class _NonFiniteError(Exception):
    pass


def read_json(path: str | Path, what: str = "JSON file", max_bytes: int = MAX_FILE_BYTES,
              max_depth: int = MAX_JSON_DEPTH, finite: bool = True) -> Any:
    """The JSON document at ``path``, read with :func:`read_file_bytes` and parsed with
    :func:`loads_json` (every failure one :class:`FileFormatError`)."""
    data = read_file_bytes(path, what, max_bytes)
    return loads_json(decode_utf8(data, path), path, max_depth, finite)
