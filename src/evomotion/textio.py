"""Safe reading of user files: bytes with a size limit, strict UTF-8, one-line errors.

Every reader of a user file goes through :func:`read_file_bytes` (missing file, directory,
unreadable, too large) and :func:`decode_utf8` / :func:`read_text_lines` (undecodable bytes
reported as ``FILE:LINE: expected UTF-8 text (byte 0xNN at column C)``), so that a hostile
file can only ever raise :class:`~evomotion.errors.FileFormatError`.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from evomotion.errors import FileFormatError

#: Default largest file a reader accepts (bytes); readers pass their own where it matters.
MAX_FILE_BYTES = 64 * 1024 * 1024


def _size_text(n: int) -> str:
    return f"{n / 2**20:g} MiB" if n >= 2**20 else f"{n} bytes"


def read_file_bytes(path: str | Path, what: str = "file",
                    max_bytes: int = MAX_FILE_BYTES) -> bytes:
    """The bytes of ``path``, or :class:`FileFormatError` (missing, not a regular file,
    unreadable, larger than ``max_bytes``). The size is checked before anything is read."""
    path = Path(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise FileFormatError(path, None, f"expected an existing {what}") from None
    except (OSError, ValueError) as e:
        raise FileFormatError(path, None, f"expected a readable {what} ({_reason(e)})") from None
    if stat.S_ISDIR(st.st_mode):
        raise FileFormatError(path, None, f"expected a {what}, got a directory")
    if st.st_size > max_bytes:
        raise FileFormatError(path, None, f"expected a {what} of at most "
                                          f"{_size_text(max_bytes)}, got {_size_text(st.st_size)}")
    try:
        with open(path, "rb") as f:
            data = f.read(max_bytes + 1)  # a pipe or a growing file cannot exceed the limit
    except (OSError, ValueError) as e:
        raise FileFormatError(path, None, f"expected a readable {what} ({_reason(e)})") from None
    if len(data) > max_bytes:
        raise FileFormatError(path, None, f"expected a {what} of at most "
                                          f"{_size_text(max_bytes)}")
    return data


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
