"""Shared by the ``--baseline REV`` benchmarks: the package at a git revision, and a child
process that measures one tree (this one, or an exported revision) and returns JSON."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def export(rev: str, into: Path, paths: tuple[str, ...] = ("src",)) -> Path:
    """``src/`` of the package as committed at ``rev`` (and the other ``paths`` of the
    repository, e.g. ``pyproject.toml``), extracted below ``into``."""
    tar = subprocess.run(["git", "-C", str(ROOT), "archive", rev, *paths], check=True,
                         capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(into)], input=tar, check=True)
    return Path(into) / "src"


def run_child(script: str, src: Path | None, env: dict | None = None) -> dict:
    """Run ``script --child OUT.json`` with ``src`` (None: this tree) first on the import
    path and return what it wrote."""
    env = dict(os.environ, **(env or {}))
    if src is not None:
        env["PYTHONPATH"] = str(src)
    with tempfile.NamedTemporaryFile(suffix=".json") as fh:
        subprocess.run([sys.executable, script, "--child", fh.name], env=env, check=True,
                       cwd=tempfile.gettempdir())
        return json.loads(Path(fh.name).read_text())
