"""A local cluster started by the project listens on the loopback interface only (issue 12)."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest


def _listeners() -> set[str]:
    out = subprocess.run(["ss", "-ltn"], capture_output=True, text=True).stdout
    return {line.split()[3] for line in out.splitlines()[1:] if line.strip()}


@pytest.mark.skipif(shutil.which("ss") is None, reason="needs iproute2's ss")
def test_local_dask_cluster_binds_loopback_only():
    pytest.importorskip("distributed")
    from evomotion.run.evaluators import make_evaluator
    from evomotion.studies import get_study

    s = get_study("functions")
    before = _listeners()
    ev = make_evaluator("dask", s.make_problem, s.problem_config(dim=4), workers=2)
    try:
        assert ev(np.zeros((4, 4))).fitness.tolist() == [0.0] * 4
        new = _listeners() - before
    finally:
        ev.close()
    assert new and all(a.startswith("127.0.0.1:") for a in new), sorted(new)
