"""What of the machine decides a CPU run's last bits, recorded beside the physics
(``physics.json``, :func:`evomotion.sim.backend.physics_record`).

MuJoCo's C engine gives the same bits on any x86-64 CPU it runs on, but numpy does not
promise that across CPUs: it picks SIMD loops at run time by the CPU's features (some float64
functions differ in the last bit on AVX-512 machines), and its BLAS (OpenBLAS, built with
``DYNAMIC_ARCH``) picks its kernels by the CPU (``Haswell``, ``SkylakeX``, ``Zen``, ...),
whose sums round differently (measured, ``benchmarks/blas_kernels.py``: a humanoid-walk run's
first generation's stats differ by up to 4e-5 under ``OPENBLAS_CORETYPE=Sandybridge`` against
``Haswell``, its controller after two generations too). A seed's run is bit-identical on
machines whose :func:`cpu_platform` agrees; a resume on another is noted in the run log.
"""

from __future__ import annotations

import ctypes
import os
import platform
from functools import lru_cache
from pathlib import Path
from typing import Any

#: the prefixes of numpy's CPU features that choose its SIMD loops
_SIMD = ("AVX", "FMA", "SSE", "ASIMD", "NEON", "SVE", "VSX", "VX")


@lru_cache(maxsize=1)
def cpu_platform() -> dict[str, Any]:
    """``cpu`` (the model, for reading only), ``numpy``, ``numpy_simd`` (the features
    numpy's dispatch sees, sorted) and ``blas`` (library, version and the kernels it chose,
    ``"?"`` where it cannot be read)."""
    import numpy as np

    try:
        from numpy._core._multiarray_umath import __cpu_features__ as features
    except ImportError:  # pragma: no cover - numpy < 2
        features = {}
    return {"cpu": _cpu_model(), "numpy": np.__version__,
            "numpy_simd": " ".join(sorted(k for k, on in features.items()
                                          if on and k.startswith(_SIMD))),
            "blas": _blas()}


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text(errors="replace").splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "?"


def _blas() -> str:
    """``name version core`` of numpy's BLAS; the core is OpenBLAS's own answer where the
    loaded library can be found (Linux), else ``?``."""
    import numpy as np

    try:
        info = np.__config__.CONFIG["Build Dependencies"]["blas"]
        name = f"{info.get('name', '?')} {info.get('version', '?')}"
    except (AttributeError, KeyError, TypeError):
        name = "? ?"
    return f"{name} {_openblas_core()}"


def _openblas_core() -> str:
    try:
        maps = Path(f"/proc/{os.getpid()}/maps").read_text(errors="replace")
    except OSError:
        return "?"
    paths = sorted({line.split()[-1] for line in maps.splitlines()
                    if "openblas" in line.lower() and line.split()[-1].startswith("/")})
    for path in paths:
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for symbol in ("scipy_openblas_get_corename64_", "scipy_openblas_get_corename",
                       "openblas_get_corename64_", "openblas_get_corename"):
            fn = getattr(lib, symbol, None)
            if fn is not None:
                fn.restype = ctypes.c_char_p
                return (fn() or b"?").decode("ascii", "replace")
    return "?"
