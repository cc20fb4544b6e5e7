"""Paths of the data files the tests carry inside the repository (a clone alone passes)."""

from pathlib import Path

FIXTURES = Path(__file__).resolve().parent / "fixtures"
WEBOTS_MOTIONS = FIXTURES / "webots-motions"  # Webots' NAO motions, Apache-2.0 (see NOTICE)
