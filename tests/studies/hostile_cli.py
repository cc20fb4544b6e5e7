"""The studies' hostile-input tests: a study's CLI run in this process, and the one-line check."""

from __future__ import annotations

import contextlib
import io

import pytest

from evomotion.cli import main


def study_cli(study: str):
    """``cli(*args) -> (exit code, stderr)`` running ``evomotion STUDY ARGS`` here."""

    def cli(*args) -> tuple[int, str]:
        err = io.StringIO()
        with contextlib.redirect_stderr(err), pytest.raises(SystemExit) as e:
            main(["evomotion", study, *map(str, args)])
        return e.value.code, err.getvalue()

    return cli


def one_error(code: int, err: str, *needles: str) -> None:
    """Exit code 2 and exactly one ``error:`` line holding every needle."""
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2 and len(lines) == 1 and lines[0].startswith("error: "), err
    for n in needles:
        assert n in lines[0], err
