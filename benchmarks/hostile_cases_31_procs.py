"""Issue 31, class 2 (process safety: ``evomotion stop`` and the studio's stop on stale locks)
and class 7 (the studio over hostile run folders).

Each case runs a driver (:data:`DRIVER`) in a private pid namespace (``unshare -pf``): pid 1
is the driver itself (it records any signal it gets), so a lock naming pid 1, 0 or -1 can
reach nothing outside the case. The driver starts a live unrelated ``sleep`` (the bystander
process), writes the hostile ``run.lock`` into a finished run's folder, then runs
``evomotion stop`` or starts ``evomotion studio`` on 127.0.0.1 with a token and sends it HTTP
requests (10 s each); it reports the answers and whether the ``sleep``, the studio and pid 1
are untouched.
"""

from __future__ import annotations

import json
import os
import socket
import sys
from pathlib import Path

from hostile_harness import Box, Result, expect_error

TOKEN = "hostile-token-31"

DRIVER = r'''
import json, os, signal, socket, subprocess, sys, time, urllib.error, urllib.request
signalled = []
for s in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP, signal.SIGUSR1, signal.SIGUSR2):
    signal.signal(s, lambda n, f: signalled.append(n))
spec = json.loads(sys.argv[1])
root = spec["root"]
res = {"responses": [], "signalled": signalled}
sleeper = subprocess.Popen(["sleep", "300"], start_new_session=True)
time.sleep(0.2)
def start_of(pid):
    with open(f"/proc/{pid}/stat") as fh:
        return int(fh.read().rsplit(")", 1)[1].split()[19])
def alive(pid):
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False
host = socket.gethostname()
with open("/proc/sys/kernel/random/boot_id") as fh:
    boot = fh.read().strip()
pid, start = sleeper.pid, start_of(sleeper.pid)
def J(**k):
    d = {"host": host, "boot": boot, "command": "evo" + "motion"}
    d.update(k)
    return json.dumps(d)
locks = {
    "json-wrong-start": J(pid=pid, start=start + 12345),
    "json-right-start": J(pid=pid, start=start),
    "old-format": f"pid {pid} on {host}",
    "other-host-json": J(pid=pid, start=start, host="another-host.example"),
    "other-host-old": f"pid {pid} on another-host.example",
    "pid0-old": f"pid 0 on {host}", "pid0-json": J(pid=0, start=1),
    "pid1-old": f"pid 1 on {host}", "pid1-json": J(pid=1, start=start_of(1)),
    "pid-1-old": f"pid -1 on {host}", "pid-1-json": J(pid=-1, start=1),
    "pid30-old": f"pid {'9' * 30} on {host}", "pid30-json": J(pid=int("9" * 30), start=1),
    "garbage": "\x00\xff{{[[ pid garbage \u2028 on",
}
if spec.get("lock"):
    with open(os.path.join(root, spec["run"], "run.lock"), "w", errors="surrogateescape") as fh:
        fh.write(locks[spec["lock"]] + "\n")
cli = [sys.executable, "-m", "evo" + "motion.cli"]
studio = None
if spec["mode"] == "cli":
    t0 = time.monotonic()
    try:
        r = subprocess.run(cli + ["stop", os.path.join(root, spec["run"])], capture_output=True,
                           text=True, timeout=10, start_new_session=True)
        res["stop"] = {"rc": r.returncode, "stderr": r.stderr[-2000:], "hang": False}
    except subprocess.TimeoutExpired:
        res["stop"] = {"rc": -999, "stderr": "", "hang": True}
    res["stop"]["wall"] = time.monotonic() - t0
else:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = dict(os.environ, EVOMOTION_STUDIO_TOKEN=spec["token"])
    log = open(spec["studio_log"], "wb")
    studio = subprocess.Popen(cli + ["studio", root, "--port", str(port)], env=env,
                              stdout=log, stderr=log, start_new_session=True)
    base = f"http://127.0.0.1:{port}"
    def get(path, api=False, method="GET", timeout=10):
        hdr = {"X-Evomotion-Token": spec["token"]} if api else {}
        req = urllib.request.Request(base + path, headers=hdr, method=method)
        t0 = time.monotonic()
        try:
            with urllib.request.urlopen(req, timeout=timeout) as r:
                code, body = r.status, r.read(4000)
        except urllib.error.HTTPError as e:
            code, body = e.code, e.read(4000)
        except Exception as e:
            code, body = type(e).__name__, b""
        return code, time.monotonic() - t0, body.decode("utf-8", "replace")
    up = False
    for _ in range(240):
        if studio.poll() is not None:
            break
        if isinstance(get(f"/files?path=zz&token={spec['token']}", timeout=2)[0], int):
            up = True
            break
        time.sleep(0.25)
    res["up"] = up
    if up:
        for path, api, method in spec["requests"]:
            path = path.replace("TOKEN", spec["token"])
            code, secs, body = get(path, api, method)
            res["responses"].append([path, code, round(secs, 2), body[:300]])
    time.sleep(0.5)
    res["studio_alive"] = alive(studio.pid)
res["sleeper_alive"] = alive(sleeper.pid)
if studio is not None:
    try:
        os.killpg(studio.pid, signal.SIGTERM)
    except OSError:
        pass
    for _ in range(50):
        p, st, ru = os.wait4(studio.pid, os.WNOHANG)
        if p:
            break
        time.sleep(0.1)
    else:
        os.killpg(studio.pid, signal.SIGKILL)
        p, st, ru = os.wait4(studio.pid, 0)
    res["studio_maxrss_kb"] = ru.ru_maxrss
sleeper.kill()
print(json.dumps(res))
'''

LOCKS = ("json-wrong-start", "json-right-start", "old-format", "other-host-json",
         "other-host-old", "pid0-old", "pid0-json", "pid1-old", "pid1-json", "pid-1-old",
         "pid-1-json", "pid30-old", "pid30-json", "garbage")


def finished_run(root: Path, name: str = "r", study: str = "functions",
                 extra: str = "") -> Path:
    """A run folder as a finished run leaves it (what the status and stop read)."""
    d = root / name
    d.mkdir(parents=True)
    (d / "config.toml").write_text(f'study = "{study}"\n{extra}')
    (d / "stats.csv").write_text("generation,evaluations,best_so_far,wall_s\n0,10,3.5,0.1\n")
    (d / "log.txt").write_text("run functions seed 0\nstopped: generations at generation 0\n")
    (d / "checkpoints").mkdir()
    return d


def drive(b: Box, spec: dict) -> tuple[Result, dict | None]:
    logs = b.tmp.parent / f"{b.tmp.name}.drv"
    logs.mkdir(exist_ok=True)
    (logs / "driver.py").write_text(DRIVER)
    spec = dict(spec, token=TOKEN, studio_log=str(logs / "studio.log"))
    b.allow = sorted({*b.allow, "runs"})
    r = b.run([sys.executable, str(logs / "driver.py"), json.dumps(spec)], limit=150,
              ns="pid")
    lines = r.stdout.strip().splitlines()
    try:
        return r, json.loads(lines[-1])
    except (IndexError, ValueError):
        return r, None


def _harm(res: dict) -> str | None:
    if res["signalled"]:
        return f"KILLED (pid 1 got signal {res['signalled'][0]})"
    if not res["sleeper_alive"]:
        return "KILLED (the unrelated sleep)"
    if res.get("studio_alive") is False:
        return "KILLED (the studio itself)"
    return None


def _http(res: dict, bad: tuple = (500,), limit_s: float = 10.0) -> str | None:
    if not res.get("up", True):
        return "FAILED (the studio did not start)"
    for path, code, secs, _ in res["responses"]:
        short = path.split("&token")[0].split("?token")[0][:30]
        if not isinstance(code, int):
            return f"HANG ({short}: {code})" if code in ("TimeoutError", "timeout") or \
                secs >= limit_s else f"FAILED ({short}: {code})"
        if code in bad:
            return f"TRACEBACK ({code} on {short})"
    return None


def stop_case(mode: str, lock: str):
    def case(b: Box) -> str:
        root = b.tmp / "runs"
        finished_run(root)
        spec = {"root": "runs", "run": "r", "lock": lock, "mode": mode,
                "requests": [["/api/runs", True, "GET"], ["/?token=TOKEN", False, "GET"],
                             ["/run?name=r&token=TOKEN", False, "GET"],
                             ["/api/stop?name=r", True, "POST"]]}
        r, res = drive(b, spec)
        if res is None:
            return expect_error(r) if r.returncode else "FAILED (no report from the driver)"
        harm = _harm(res)
        if harm:
            return harm
        if mode == "cli":
            s = res["stop"]
            rr = Result([], s["rc"], "", s["stderr"], s["wall"], hang=s["hang"])
            return expect_error(rr)
        http = _http(res)
        if http:
            return http
        code, body = res["responses"][-1][1], res["responses"][-1][3]
        if code == 200:
            return "SILENT (stop answered 200)"
        try:
            msg = json.loads(body)["error"]
        except (ValueError, KeyError, TypeError):
            return f"FAILED (stop answered {code}: {body[:30]!r})"
        return "one-line error" if code == 400 and "\n" not in msg else f"exit {code}"
    return case


def studio_case(setup, requests: list, check=None):
    """``setup(root)`` makes the hostile run folders; every request must answer within 10 s
    and never 500; ``check(res)`` may add a verdict."""
    def case(b: Box) -> str:
        root = b.tmp / "runs"
        root.mkdir()
        setup(root)
        r, res = drive(b, {"root": "runs", "run": None, "lock": None, "mode": "studio",
                           "requests": requests})
        if res is None:
            return "FAILED (no report from the driver)"
        v = _harm(res) or _http(res)
        if v:
            return v
        return (check(res) if check else None) or "ok"
    return case


def _fifo_log(root: Path) -> None:
    d = finished_run(root, "fifo-log")
    (d / "log.txt").unlink()
    os.mkfifo(d / "log.txt")
    finished_run(root, "fine")


def _robot(path: str):
    def setup(root: Path) -> None:
        from hostile_cases_31 import MOTIONS

        d = finished_run(root, "robot", "humanoid-step", f'\n[problem]\nrobot = "{path}"\n')
        (d / "best.motion").write_bytes((MOTIONS / "Shoot.motion").read_bytes())
        if path == "fifo.toml":
            os.mkfifo(root / "fifo.toml")
    return setup


def _lock30(root: Path) -> None:
    host = socket.gethostname()
    (finished_run(root, "r") / "run.lock").write_text(f"pid {'9' * 30} on {host}\n")
    (finished_run(root, "j") / "run.lock").write_text(
        json.dumps({"pid": int("9" * 30), "host": host, "start": 1}) + "\n")


def _device_links(root: Path) -> None:
    d = finished_run(root, "links")
    for name in ("stats.csv", "log.txt", "run.lock"):
        (d / name).unlink(missing_ok=True)
        os.symlink("/dev/zero", d / name)


def _sparse(root: Path) -> None:
    d = finished_run(root, "sparse")
    for name in ("stats.csv", "log.txt"):
        with open(d / name, "ab") as fh:
            fh.truncate(8 << 30)  # 8 GiB of holes


def _ok_codes(*codes: int):
    def check(res: dict) -> str | None:
        for path, code, _, _ in res["responses"]:
            if code not in codes:
                return f"FAILED ({path.split('&token')[0][:30]}: {code})"
        return None
    return check


RUNS = [["/api/runs", True, "GET"], ["/?token=TOKEN", False, "GET"]]


def cases() -> dict:
    out = {}
    for mode, label in (("cli", "evomotion stop"), ("studio", "studio /api/stop")):
        for lock in LOCKS:
            out[f"P {label}: lock {lock}"] = stop_case(mode, lock)
    out.update({
        "S1 studio: a run whose log.txt is a FIFO (runs list)":
            studio_case(_fifo_log, RUNS, _ok_codes(200)),
        "S2 studio: problem.robot = /dev/zero (run page, memory)":
            studio_case(_robot("/dev/zero"), [["/run?name=robot&token=TOKEN", False, "GET"],
                                              *RUNS], _ok_codes(200)),
        "S3 studio: problem.robot a FIFO (run page)":
            studio_case(_robot("fifo.toml"), [["/run?name=robot&token=TOKEN", False, "GET"],
                                              *RUNS], _ok_codes(200)),
        "S4 studio: /run?name=f1%00": studio_case(
            lambda root: finished_run(root, "f1"), [["/run?name=f1%00&token=TOKEN", False,
                                                     "GET"]]),
        "S5 studio: /files?path=%00": studio_case(
            lambda root: finished_run(root, "f1"), [["/files?path=%00&token=TOKEN", False,
                                                     "GET"],
                                                    ["/files?path=f1%2F%00&token=TOKEN", False,
                                                     "GET"]]),
        "S6 studio: a 30-digit pid in run.lock (list, page, stop)": studio_case(
            _lock30, [*RUNS, ["/run?name=r&token=TOKEN", False, "GET"],
                      ["/api/stop?name=r", True, "POST"], ["/api/stop?name=j", True, "POST"]],
            None),
        "S7 studio: stats.csv, log.txt, run.lock symlinks to /dev/zero": studio_case(
            _device_links, [*RUNS, ["/run?name=links&token=TOKEN", False, "GET"]],
            _ok_codes(200)),
        "S8 studio: 8 GiB sparse stats.csv and log.txt": studio_case(
            _sparse, [*RUNS, ["/run?name=sparse&token=TOKEN", False, "GET"]], _ok_codes(200)),
    })
    return out
