"""Shared values of the studio's tests."""

from __future__ import annotations

import shutil
import socket
import urllib.error
import urllib.request

from evomotion.studies import get_study

TOKEN = "test-token-0123456789"
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--no-first-run",
        "--disable-component-update", "--disable-sync"]


def smoke_sets(name: str) -> list[str]:
    extra = {"quadruped-plan": ["run.generations=400"], "arm-ik": ["run.history_every=1"],
             "humanoid-step": ["run.history_every=1"],
             "humanoid-walk-open-loop": ["run.history_every=1"],
             "biped-kick": ["run.history_every=1"],
             "humanoid-repertoire": ["run.history_every=1"]}
    return [*get_study(name).smoke, "run.generations=5", "run.wall_seconds=0",
            "run.videos=false",
            *extra.get(name, [])]


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def get(url: str, headers: dict | None = None, method: str = "GET") -> tuple[int, bytes]:
    req = urllib.request.Request(url, headers=headers or {}, method=method)
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            return r.status, r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.read()


def wait_until_up(proc, url: str, headers: dict | None = None, timeout_s: float = 60) -> None:
    """Wait until the studio process ``proc`` answers ``url`` with 200; fail the test when it
    exits first or does not answer within ``timeout_s`` (then it is killed)."""
    import time

    import pytest

    deadline = time.time() + timeout_s
    while time.time() < deadline:
        try:
            if get(url, headers)[0] == 200:
                return
        except OSError:
            pass
        if proc.poll() is not None:
            pytest.fail(f"the studio exited: {proc.stdout.read().decode()[-2000:]}")
        time.sleep(0.3)
    proc.kill()
    pytest.fail(f"the studio did not answer within {timeout_s:g} s")

