"""The import-layer contract "no study imports another" (pyproject.toml, run in CI by
``lint-imports``) lists every study package: one left out of it (three were, until
2026-12-07) could import another study without CI noticing."""

from __future__ import annotations

import tomllib
from pathlib import Path

import evomotion.studies

ROOT = Path(__file__).resolve().parents[2]


def test_the_independence_contract_lists_every_study_package():
    contracts = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]
    (independence,) = [c for c in contracts["contracts"] if c["type"] == "independence"]
    listed = set(independence["modules"])
    folder = Path(evomotion.studies.__file__).parent
    packages = {f"evomotion.studies.{p.name}" for p in folder.iterdir()
                if (p / "__init__.py").is_file()}
    assert len(packages) >= 11
    assert packages == listed, (f"missing: {sorted(packages - listed)}; "
                                f"not packages: {sorted(listed - packages)}")
