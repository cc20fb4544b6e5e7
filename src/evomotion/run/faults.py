"""Fault injection for checking the run loop's promises: a run interrupted (Ctrl-C) or killed
(``kill -9``) during a given step, exactly there, whatever the study (tests, benchmarks)."""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator
from contextlib import contextmanager

from evomotion.run import runner

HOW = {"interrupt": None, "sigint": signal.SIGINT, "sigkill": signal.SIGKILL}


@contextmanager
def fault_at(step: int, how: str = "interrupt") -> Iterator[None]:
    """Within the block, every run's driver fails when step ``step`` (0-based) starts:
    ``interrupt`` raises ``KeyboardInterrupt`` there, ``sigint`` / ``sigkill`` send that signal
    to this process."""
    if how not in HOW:
        raise ValueError(f"unknown fault {how!r}; available: {', '.join(HOW)}")
    build = runner.build_driver

    def faulty(*args, **kwargs):
        driver = build(*args, **kwargs)
        real, count = driver.step, {"n": 0}

        def step_once(*a, **k):
            count["n"] += 1
            if count["n"] == step + 1:
                if HOW[how] is None:
                    raise KeyboardInterrupt
                os.kill(os.getpid(), HOW[how])
            return real(*a, **k)

        driver.step = step_once
        return driver

    runner.build_driver = faulty
    try:
        yield
    finally:
        runner.build_driver = build
