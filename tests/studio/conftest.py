"""Fixtures of the studio's end-to-end tests: a folder with a finished run of every study, the
studio serving it, and headless Chromium (Debian's, installed by scripts/install.sh test)
driven by Playwright."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from studio_helpers import ARGS, CHROMIUM, TOKEN, free_port, smoke_sets, wait_until_up  # noqa: E402

from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.studies import STUDIES, get_study


@pytest.fixture(scope="session")
def runs_root(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("runs")
    for name in sorted(STUDIES):
        s = get_study(name)
        run_study(s, resolve_config(s, None, smoke_sets(name)), root / name, quiet=True)
    return root


@pytest.fixture(scope="session")
def studio(runs_root):
    """``(base_url, runs_root)`` of a studio serving ``runs_root``."""
    pytest.importorskip("nicegui")
    port = free_port()
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST")}
    env["EVOMOTION_STUDIO_TOKEN"] = TOKEN
    proc = subprocess.Popen([sys.executable, "-m", "evomotion.cli", "studio", str(runs_root),
                             "--port", str(port)], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT)
    base = f"http://127.0.0.1:{port}"
    wait_until_up(proc, f"{base}/?token={TOKEN}")
    yield base, runs_root
    proc.terminate()
    try:
        proc.wait(10)
    except subprocess.TimeoutExpired:
        proc.kill()


@pytest.fixture(scope="session")
def chromium():
    sync_api = pytest.importorskip("playwright.sync_api")
    if not Path(CHROMIUM).exists():
        pytest.skip("Debian's chromium is not installed (scripts/install.sh test installs it)")
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield browser
        browser.close()


def _nicegui_echart_race(text: str) -> bool:
    """NiceGUI's echart disposes ``this.chart`` in ``beforeUnmount``, which its async
    ``mounted`` sets only after a timer: a chart replaced before that (a study view redrawn
    while a loaded browser is slow) logs this TypeError (zauberzeug/nicegui#4427). Nothing is
    lost: the replacement chart draws."""
    return "reading 'dispose'" in text and "echart.js" in text and "beforeUnmount" in text


@pytest.fixture
def page(chromium, studio):
    """A page whose console errors and uncaught exceptions fail the test (but NiceGUI's own
    echart unmount race, :func:`_nicegui_echart_race`)."""
    context = chromium.new_context(viewport={"width": 1300, "height": 1000})
    pg = context.new_page()
    errors: list[str] = []
    pg.on("console", lambda m: errors.append(m.text)
          if m.type == "error" and not _nicegui_echart_race(m.text) else None)
    pg.on("pageerror", lambda e: errors.append(f"uncaught: {e}")
          if not _nicegui_echart_race(f"{e} {getattr(e, 'stack', '')}") else None)
    base, _ = studio
    pg.goto(f"{base}/?token={TOKEN}")  # sets the token cookie
    yield pg
    context.close()
    assert not errors, f"browser console errors: {errors[:5]}"
