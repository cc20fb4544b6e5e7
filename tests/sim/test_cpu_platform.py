"""The host facts a CPU run's bits depend on (sim/cpu_platform.py), recorded in physics.json,
and a resume on another host noted."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys

import pytest

from evomotion.sim.cpu_platform import cpu_platform

ON_X86_LINUX = sys.platform.startswith("linux") and platform.machine() in ("x86_64", "AMD64")


def _in_a_process(env: dict[str, str], code: str) -> str:
    return subprocess.run([sys.executable, "-c", code], env={**os.environ, **env},
                          capture_output=True, text=True, check=True, timeout=120).stdout


def test_the_record_names_numpy_its_simd_features_and_blas():
    rec = cpu_platform()
    assert set(rec) == {"cpu", "numpy", "numpy_simd", "blas"}
    import numpy as np

    assert rec["numpy"] == np.__version__ and rec["cpu"]
    if ON_X86_LINUX:
        assert "SSE2" in rec["numpy_simd"].split()
    json.dumps(rec)  # plain text, for physics.json


@pytest.mark.skipif(not ON_X86_LINUX, reason="OpenBLAS core types are x86 ones")
def test_the_blas_kernels_openblas_chose_are_read_back():
    code = "from evomotion.sim.cpu_platform import cpu_platform; print(cpu_platform()['blas'])"
    here = _in_a_process({}, code).strip()
    if here.endswith(" ?"):
        pytest.skip(f"numpy's BLAS is not an OpenBLAS whose core can be read: {here}")
    forced = _in_a_process({"OPENBLAS_CORETYPE": "Nehalem"}, code).strip()
    assert forced.endswith(" Nehalem") and forced.rsplit(" ", 1)[0] == here.rsplit(" ", 1)[0]
