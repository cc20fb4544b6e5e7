"""The served studio over hostile run folders and locks (issue 31), at the HTTP level (no
browser): the runs page, ``/api/runs`` and ``/api/stop`` answer without a 500 for any lock,
a live unrelated process named by a stale lock survives stop, a FIFO log does not block the
list, a ``/dev/zero`` robot does not bloat the studio, and NUL in a name is a 404/400."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
from urllib.parse import quote

import pytest
from hostile_helpers import fake_run, hostile_root, json_lock, stale_locks
from studio_helpers import TOKEN, free_port, get, wait_until_up

API = {"X-Evomotion-Token": TOKEN}
HOST = socket.gethostname()
LOCKS = {"pid0": f"pid 0 on {HOST}\n", "pid1": f"pid 1 on {HOST}\n",
         "pid30": f"pid {'9' * 30} on {HOST}\n", "json-pid0": json_lock(0, start=1),
         "json-pid30": json_lock(int("9" * 30), start=1), "garbage": "\x00\xff{{{[[[ pid",
         "deep": "[" * 100000}


def _rss_kb(pid: int, field: str = "VmRSS") -> int:
    with open(f"/proc/{pid}/status") as fh:
        for line in fh:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    return 0


@pytest.fixture(scope="module")
def hostile_studio(tmp_path_factory):
    """``(base_url, root, studio process, sleeper process)``."""
    pytest.importorskip("nicegui")
    root = hostile_root(tmp_path_factory.mktemp("hostile") / "runs")
    sleeper = subprocess.Popen(["sleep", "120"])
    for name, text in {**LOCKS, **{f"stale-{k}": v
                                   for k, v in stale_locks(sleeper.pid).items()}}.items():
        (fake_run(root, name) / "run.lock").write_text(text, errors="surrogateescape")
    port = free_port()
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST")}
    env["EVOMOTION_STUDIO_TOKEN"] = TOKEN
    proc = subprocess.Popen([sys.executable, "-m", "evomotion.cli", "studio", str(root),
                             "--port", str(port)], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, cwd=root)
    base = f"http://127.0.0.1:{port}"
    try:
        wait_until_up(proc, f"{base}/api/runs", API)
        yield base, root, proc, sleeper
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
        sleeper.kill()
        sleeper.wait()


def test_runs_list_and_page_answer_for_every_folder(hostile_studio):
    base, root, proc, _ = hostile_studio
    t0 = time.monotonic()
    code, body = get(f"{base}/api/runs", API)
    assert code == 200 and time.monotonic() - t0 < 8
    rows = {r["name"]: r for r in json.loads(body)}
    assert set(rows) == {p.name for p in root.iterdir() if p.is_dir()}
    assert rows["fifo-log"]["status"] == "interrupted"
    for name in LOCKS:
        assert rows[name]["status"] == "finished", name  # no owner: the log decides
    for name, row in rows.items():
        if name.startswith("stale-other-host"):
            assert row["status"] == "remote", name
        elif name.startswith("stale-"):
            assert row["status"] == "stale" and "stale lock" in row["stop_reason"], name
    for url in ("/", "/?study=%00", "/?study=functions", "/compare?runs=fifo-log,pid30"):
        assert get(f"{base}{url}&token={TOKEN}" if "?" in url
                   else f"{base}{url}?token={TOKEN}")[0] == 200, url
    assert proc.poll() is None


def test_stop_is_refused_for_every_lock_and_signals_nobody(hostile_studio):
    base, root, proc, sleeper = hostile_studio
    names = [*LOCKS, *(p.name for p in root.iterdir() if p.name.startswith("stale-"))]
    for name in names:
        code, body = get(f"{base}/api/stop?name={quote(name)}", API, "POST")
        assert code == 400, (name, code, body[:300])
        msg = json.loads(body)["error"]
        assert "\n" not in msg, name
    time.sleep(0.2)
    assert sleeper.poll() is None, "the unrelated process was signalled"
    assert proc.poll() is None, "the studio was signalled"
    for name in ("stale-wrong-start", "pid0", "fine"):
        code, _ = get(f"{base}/run?name={quote(name)}&token={TOKEN}")
        assert code == 200, name


@pytest.mark.parametrize("url", ["/run?name=f1%00", "/run?name=%00", "/run?name=a%0Ab",
                                 "/run?name=no-such-run", "/run?name=..%2F..%2Fetc",
                                 "/files?path=%00", "/files?path=fine%2F%00",
                                 "/files?path=" + "x" * 5000, "/files?path=fine/%ff%fe"],
                         ids=lambda u: u[:40])
def test_bad_names_are_404_never_500(hostile_studio, url):
    base, *_ = hostile_studio
    assert get(f"{base}{url}&token={TOKEN}")[0] == 404


@pytest.mark.parametrize("action", ["stop", "resume"])
def test_bad_names_in_actions_are_400(hostile_studio, action):
    base, *_ = hostile_studio
    for name in ("%00", "f1%00", "a%0Ab", "%ff", "x" * 3000):
        assert get(f"{base}/api/{action}?name={name}", API, "POST")[0] == 400, name


@pytest.mark.parametrize("query", ["/api/extend?name=fine&generations=ten",
                                   "/api/extend?name=fine&generations=1.5",
                                   "/api/extend?name=fine", "/api/stop", "/api/resume?x=1"])
def test_mistyped_or_missing_parameters_are_one_line_400(hostile_studio, query):
    """FastAPI answers a bad query parameter with a 422 document; the studio's API says it in
    one line, as every other refusal (issue 35)."""
    base, *_ = hostile_studio
    status, body = get(f"{base}{query}", API, "POST")
    assert status == 400
    error = json.loads(body)["error"]
    assert "\n" not in error and len(error) < 300
    assert ("generations" if "extend" in query else "name") in error, error
    if "=ten" in query:
        assert "'ten'" in error and "integer" in error


def test_a_dev_zero_robot_page_answers_without_bloating(hostile_studio):
    base, root, proc, _ = hostile_studio
    get(f"{base}/run?name=fine&token={TOKEN}")  # warm: the page's modules are loaded
    before = _rss_kb(proc.pid)
    for name in ("robot-dev-zero", "robot-fifo-robot.toml", "robot-huge-robot.toml",
                 "fifo-everything", "device-links", "huge-sparse", "fifo-config"):
        t0 = time.monotonic()
        code, body = get(f"{base}/run?name={quote(name)}&token={TOKEN}")
        assert code == 200 and time.monotonic() - t0 < 8, name
    code, body = get(f"{base}/run?name=robot-dev-zero&token={TOKEN}")
    assert b"problem.robot" in body and b"character device" in body
    assert (_rss_kb(proc.pid) - before) / 1024 < 200
    assert _rss_kb(proc.pid, "VmHWM") / 1024 < 1024
    assert proc.poll() is None


def _post_json(url: str, body) -> tuple[int, dict]:
    import urllib.error
    import urllib.request

    req = urllib.request.Request(url, data=json.dumps(body).encode(), method="POST",
                                 headers={**API, "Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(req, timeout=60) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read())


def test_api_start_starts_a_run_and_refuses_bad_bodies(hostile_studio):
    """``POST /api/start`` (docs/studio.md) starts a run (it answered 422 to everything before
    issue 35: FastAPI took the request for a query parameter); a bad body is one line, 400."""
    base, root, *_ = hostile_studio
    for body, msg in (([1, 2], "expected a JSON object"), ({"study": 3}, "study:"),
                      ({"study": "no-such-study"}, "no-such-study"),
                      ({"study": "functions", "sets": "run.generations=1"}, "sets:"),
                      ({"study": "functions", "tags": "a"}, "tags:"),
                      ({"study": "functions", "tags": ["ok", "a b"]}, "tag 'a b'")):
        code, res = _post_json(f"{base}/api/start", body)
        assert code == 400 and msg in res["error"] and "\n" not in res["error"], (body, res)
    code, res = _post_json(f"{base}/api/start", {"study": "functions",
                                                 "sets": ["run.generations=2"],
                                                 "tags": ["api", "smoke"]})
    assert code == 200, res
    run = root / res["name"]
    assert (run / "config.toml").is_file() and res["pid"] > 0
    assert (run / "tags.txt").read_text() == "api\nsmoke\n"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not (run / "best.json").exists():
        time.sleep(0.2)
    assert (run / "best.json").exists()
