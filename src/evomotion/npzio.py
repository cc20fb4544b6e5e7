"""Reading ``.npz`` files without trusting them.

``numpy.load`` allocates whatever shape an array's header declares before it reads a byte of
data, so a 200-byte file can ask for terabytes. :func:`read_npz` reads the file once (a regular
file, within a size limit), then checks every member before any array is made: a ``.npy``
name, a declared uncompressed size within the limit, a header numpy can parse, no Python
objects, and a declared shape whose bytes are exactly what the member holds. Only then are
the arrays read. Every failure is one :class:`~evomotion.errors.FileFormatError`.
"""

from __future__ import annotations

import io
import math
import zipfile
from pathlib import Path

import numpy as np

from evomotion.errors import FileFormatError
from evomotion.textio import read_file_bytes

#: the largest npz file, and the largest sum of its arrays' bytes, a reader accepts by default
MAX_NPZ_BYTES = 256 * 1024 * 1024
MAX_MEMBERS = 4096
MAX_ELEMENTS = 1 << 31
#: the dtype kinds a reader accepts: booleans, integers, floats, complex, text
KINDS = "biufcUS"


def read_npz(path: str | Path, what: str = "npz file", max_bytes: int = MAX_NPZ_BYTES,
             max_members: int = MAX_MEMBERS) -> dict[str, np.ndarray]:
    """The arrays of the npz file at ``path`` by name (see the module)."""
    data = read_file_bytes(path, what, max_bytes)
    return loads_npz(data, path, what, max_bytes, max_members)


def loads_npz(data: bytes, path: str | Path, what: str = "npz file",
              max_bytes: int = MAX_NPZ_BYTES, max_members: int = MAX_MEMBERS
              ) -> dict[str, np.ndarray]:
    def bad(msg: str) -> FileFormatError:
        return FileFormatError(path, None, f"expected a readable {what}: {msg}")

    try:
        zf = zipfile.ZipFile(io.BytesIO(data))
        infos = zf.infolist()
    except (zipfile.BadZipFile, OSError, ValueError, EOFError, NotImplementedError) as e:
        raise bad(f"not a zip archive ({type(e).__name__})") from None
    if len(infos) > max_members:
        raise bad(f"{len(infos)} members, at most {max_members}")
    total = sum(i.file_size for i in infos)
    if total > max_bytes:
        raise bad(f"its arrays declare {total} bytes, at most {max_bytes}")
    out: dict[str, np.ndarray] = {}
    for info in infos:
        name = info.filename
        if not name.endswith(".npy") or name[:-4] in out:
            raise bad(f"member {name[:60]!r}: expected a unique NAME.npy")
        try:
            with zf.open(info) as fh:
                _check_header(fh, info.file_size, name)
            with zf.open(info) as fh:
                raw = fh.read(info.file_size + 1)
            if len(raw) != info.file_size:
                raise ValueError("the member is not its declared size")
            arr = np.lib.format.read_array(io.BytesIO(raw), allow_pickle=False)
        except FileFormatError:
            raise
        except (zipfile.BadZipFile, OSError, ValueError, EOFError, TypeError, KeyError,
                OverflowError, NotImplementedError, RuntimeError) as e:
            raise bad(f"member {name[:60]!r}: {type(e).__name__}: {str(e)[:80]}") from None
        out[name[:-4]] = arr
    return out


def _check_header(fh, size: int, name: str) -> None:
    """The ``.npy`` header of member ``name`` declares an array that fits in the bytes after
    it (``size``: the whole member; a header's own bytes once counted as data, so a member
    2 elements short failed later, as an EOF, not here)."""
    version = np.lib.format.read_magic(fh)
    if version == (1, 0):
        shape, _, dtype = np.lib.format.read_array_header_1_0(fh)
    elif version in ((2, 0), (3, 0)):
        shape, _, dtype = np.lib.format.read_array_header_2_0(fh)
    else:
        raise ValueError(f"unknown npy version {version}")
    if dtype.hasobject or dtype.kind not in KINDS or dtype.fields is not None:
        raise ValueError(f"holds {dtype} values (expected numbers or text)")
    n = math.prod(int(d) for d in shape)
    need = n * dtype.itemsize
    if n > 0 and dtype.itemsize == 0 or n > MAX_ELEMENTS:
        raise ValueError(f"declares shape {tuple(shape)[:8]} of {dtype} (too many elements)")
    data = size - fh.tell()  # the member's bytes after its header
    if need > data:
        raise ValueError(f"declares shape {tuple(shape)[:8]} ({need} bytes) but holds "
                         f"{data} bytes")
