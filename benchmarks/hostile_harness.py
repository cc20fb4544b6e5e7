"""The sandbox of issue 31's hostile cases (:mod:`hostile_cases_31`): every command runs in a
fresh temporary folder beside a bystander tree, under a time limit, with its memory measured,
and the case's outcome is the worst of what happened.

- **hang**: each command under test gets :data:`LIMIT_S` (10 s); past it, its process group
  and every descendant are killed (``HANG``).
- **memory**: the child runs under :class:`subprocess.Popen` and is reaped with
  :func:`os.wait4`; its ``ru_maxrss`` (KiB; the largest of it and its reaped descendants) above
  1 GiB is ``MEMORY``. A watchdog also kills any descendant tree past :data:`KILL_KB`, so a
  runaway reader cannot take the shared machine down.
- **nothing outside touched**: the case folder holds a bystander tree (a project folder with
  ``config.toml``, ``thesis.tex``, ``src/``, ``.git/``; an ``outside/`` folder that symlinks
  may point at); names, kinds, link targets and SHA-256 of everything in the case folder are
  compared before and after, except the paths the case may write (``box.allow``), and
  ``/dev/null`` must still be the null character device. Anything else is ``TOUCHED``.

Commands that might touch ``/dev`` run in a private mount namespace with a private ``/dev``
(``unshare -m``; the real ``/dev/null`` is checked after every case anyway); commands that
might signal a pid named by a hostile lock run in a private pid namespace (``unshare -pf``),
so that pid 1, 0 or -1 name nothing outside the case.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import shlex
import signal
import stat
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

LIMIT_S = 10.0
SETUP_LIMIT_S = 600.0
MEM_KB = 1 << 20  # 1 GiB: MEMORY above it
KILL_KB = 3 << 19  # 1.5 GiB: the watchdog kills above it
#: worst first; anything not listed (ok, one-line error) ranks last
ORDER = ("TOUCHED", "KILLED", "HANG", "MEMORY", "TRACEBACK", "SILENT", "LATE", "FAILED",
         "exit", "n/a", "setup failed", "case failed")
GOOD = ("ok", "one-line error")

#: a private /dev for commands that might replace /dev/null: the report names its kind after
_PRIVATE_DEV = (
    "mount -t tmpfs -o size=1m,mode=755 hostile-dev /dev && "
    "mknod -m 666 /dev/null c 1 3 && mknod -m 666 /dev/zero c 1 5 && "
    "mknod -m 444 /dev/urandom c 1 9 && mknod -m 444 /dev/random c 1 8 && "
    "mkdir /dev/shm && mount -t tmpfs -o size=64m hostile-shm /dev/shm && "
    "ln -s /proc/self/fd /dev/fd || exit 97; "
    '"$@"; rc=$?; stat -c "%F %t:%T" /dev/null > "$HOSTILE_DEVNULL"; exit $rc')


class SetupError(Exception):
    """A case's own preparation failed (reported as ``setup failed``)."""


@dataclass
class Result:
    """A finished command, like :class:`subprocess.CompletedProcess`, with its measures."""

    args: list
    returncode: int
    stdout: str
    stderr: str
    wall: float = 0.0
    maxrss_kb: int = 0
    hang: bool = False
    memory: bool = False
    extra: dict = field(default_factory=dict)

    def error_lines(self) -> list[str]:
        return [ln for ln in self.stderr.splitlines() if ln.startswith("error:")]


def _children_map() -> dict[int, list[int]]:
    kids: dict[int, list[int]] = {}
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open(f"/proc/{d}/stat", "rb") as fh:
                text = fh.read(512).decode("ascii", "replace")
            ppid = int(text.rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            continue
        kids.setdefault(ppid, []).append(int(d))
    return kids


def descendants(pid: int) -> list[int]:
    kids = _children_map()
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        for k in kids.get(p, []):
            out.append(k)
            todo.append(k)
    return out


def _status_kb(pid: int | str, field: str = "VmRSS") -> int:
    try:
        with open(f"/proc/{pid}/status", "rb") as fh:
            for line in fh.read(8192).decode("ascii", "replace").splitlines():
                if line.startswith(field + ":"):
                    return int(line.split()[1])
    except (OSError, ValueError):
        pass
    return 0


def _kill_tree(pid: int) -> None:
    for p in [pid, *descendants(pid)]:
        with contextlib.suppress(OSError):
            os.kill(p, signal.SIGKILL)
    with contextlib.suppress(OSError):
        os.killpg(pid, signal.SIGKILL)


def run_command(argv: list[str], cwd: Path, env: dict, limit: float, logs: Path,
                stdin_path: str | None = None, on_tick=None) -> Result:
    """Run ``argv`` in its own session; kill it and its descendants past ``limit`` seconds or
    :data:`KILL_KB`; its exit status, output, wall time and peak RSS. ``on_tick(seconds)``,
    called every few milliseconds, may return True to have it killed (SIGKILL).

    The peak is ``wait4``'s ``ru_maxrss``, except that Linux starts a child's count at the RSS
    of the process it was forked from (this harness): where ``ru_maxrss`` does not exceed the
    harness's own peak, the child's own high-water marks (``VmHWM``, polled every 0.1 s over
    it and its descendants) are taken instead."""
    logs.mkdir(parents=True, exist_ok=True)
    out_p, err_p = logs / "stdout", logs / "stderr"
    own_kb = _status_kb("self", "VmHWM")
    with open(out_p, "wb") as out, open(err_p, "wb") as err, \
            open(stdin_path or os.devnull, "rb") as inp:
        t0 = time.monotonic()
        p = subprocess.Popen(argv, cwd=cwd, env=env, stdout=out, stderr=err, stdin=inp,
                             start_new_session=True)
        hang = memory = False
        status, ru, polled = 0, None, 0
        next_mem = t0
        while True:
            pid, status, ru = os.wait4(p.pid, os.WNOHANG)
            if pid:
                break
            now = time.monotonic()
            if now - t0 > limit:
                hang = True
                _kill_tree(p.pid)
                _, status, ru = os.wait4(p.pid, 0)
                break
            if on_tick is not None and on_tick(now - t0):
                _kill_tree(p.pid)
                _, status, ru = os.wait4(p.pid, 0)
                break
            if now >= next_mem:
                next_mem = now + 0.1
                tree = [p.pid, *descendants(p.pid)]
                polled = max(polled, *(_status_kb(q_, "VmHWM") for q_ in tree))
                if sum(_status_kb(q_) for q_ in tree) > KILL_KB:
                    memory = True
                    _kill_tree(p.pid)
                    _, status, ru = os.wait4(p.pid, 0)
                    break
            time.sleep(0.005 if on_tick is not None else 0.02)
        wall = time.monotonic() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    for q_ in descendants(p.pid):  # a detached grandchild left behind (not ours to keep)
        with contextlib.suppress(OSError):
            os.kill(q_, signal.SIGKILL)
    ru_kb = ru.ru_maxrss if ru is not None else 0
    rss = ru_kb if ru_kb > own_kb + 1024 else polled
    return Result(argv, p.returncode, out_p.read_bytes().decode("utf-8", "replace"),
                  err_p.read_bytes().decode("utf-8", "replace"), wall, rss,
                  hang, memory or rss > MEM_KB)


# --- the case folder ---------------------------------------------------------------------

BYSTANDERS = {
    "project/config.toml": b"[run]\nseed = 1\n",
    "project/thesis.tex": b"\\documentclass{article}\n% three years of work\n",
    "project/src/main.py": b"print('hello')\n",
    "project/.git/HEAD": b"ref: refs/heads/main\n",
    "project/.git/config": b"[core]\n\tbare = false\n",
    "outside/keep.txt": b"keep me\n",
    "outside/data/x.bin": bytes(range(256)) * 16,
}


def make_bystanders(root: Path) -> None:
    for rel, data in BYSTANDERS.items():
        p = root / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_bytes(data)


def _entry(path: str, st: os.stat_result) -> tuple:
    mode = st.st_mode
    if stat.S_ISLNK(mode):
        return ("link", os.readlink(path))
    if stat.S_ISDIR(mode):
        return ("dir",)
    if stat.S_ISREG(mode):
        if st.st_size > 64 << 20:  # a huge (sparse) file of a case: size and time suffice
            return ("file", st.st_size, st.st_mtime_ns)
        h = hashlib.sha256()
        try:
            with open(path, "rb") as fh:
                for chunk in iter(lambda: fh.read(1 << 20), b""):
                    h.update(chunk)
        except OSError as e:
            return ("file", "unreadable", e.errno)
        return ("file", h.hexdigest())
    return (stat.filemode(mode)[0], st.st_rdev)


def snapshot(root: Path, allow: list[str]) -> dict[str, tuple]:
    """Every path below ``root`` but those under an allowed one: kind, target or digest."""
    allowed = [a.rstrip("/") for a in allow]
    out: dict[str, tuple] = {}
    todo = [""]
    while todo:
        rel = todo.pop()
        full = os.path.join(root, rel) if rel else str(root)
        try:
            names = os.listdir(full)
        except OSError:
            continue
        for n in names:
            r = f"{rel}/{n}" if rel else n
            if r == ".logs" or any(r == a or r.startswith(a + "/") for a in allowed):
                continue
            try:
                st = os.lstat(os.path.join(full, n))
            except OSError:
                continue
            out[r] = _entry(os.path.join(full, n), st)
            if stat.S_ISDIR(st.st_mode):
                todo.append(r)
    return out


def devnull_ok() -> bool:
    st = os.stat("/dev/null")
    return stat.S_ISCHR(st.st_mode) and st.st_rdev == os.makedev(1, 3)


def restore_devnull() -> None:
    with contextlib.suppress(OSError):
        os.remove("/dev/null")
    os.mknod("/dev/null", 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    os.chmod("/dev/null", 0o666)


class Box:
    """One case's folder and its commands. ``box.allow``: paths (relative) the case may
    change; the "before" snapshot is taken at the first command under test (:meth:`cli`,
    :meth:`py`, :meth:`run`), after the case prepared its files."""

    def __init__(self, src: Path | None, root: Path, label: str, cache: Path) -> None:
        self.env = dict(os.environ)
        self.env.pop("EVOMOTION_STUDIO_TOKEN", None)
        if src is not None:
            self.env["PYTHONPATH"] = str(src)
        self.src = src
        self.tmp = root
        self.label = label
        self.cache = cache
        self.allow: list[str] = []
        self.before: dict | None = None
        self.results: list[Result] = []
        self.mounts: list[Path] = []
        self.notes: list[str] = []
        self._n = 0
        make_bystanders(root)

    # -- commands
    def _logs(self) -> Path:
        self._n += 1
        return self.tmp.parent / f"{self.tmp.name}.logs" / str(self._n)

    def arm(self) -> None:
        if self.before is None:
            self.before = snapshot(self.tmp, self.allow)

    def run(self, argv: list[str], limit: float = LIMIT_S, ns: str | None = None,
            stdin: str | None = None) -> Result:
        """A command under test (``ns``: ``"dev"`` private /dev, ``"pid"`` private pids)."""
        self.arm()
        env = dict(self.env)
        report = None
        if ns == "dev":
            report = self.tmp.parent / f"{self.tmp.name}.devnull"
            env["HOSTILE_DEVNULL"] = str(report)
            argv = ["unshare", "-m", "--propagation", "private", "sh", "-c", _PRIVATE_DEV,
                    "sh", *argv]
        elif ns == "pid":
            argv = ["unshare", "-pf", "--mount-proc", *argv]
        r = run_command(argv, self.tmp, env, limit, self._logs(), stdin)
        if report is not None:
            kind = report.read_text().strip() if report.exists() else "no report"
            r.extra["devnull"] = kind
        self.results.append(r)
        return r

    def cli(self, *args: str, limit: float = LIMIT_S, ns: str | None = None) -> Result:
        return self.run([sys.executable, "-m", "evomotion.cli", *args], limit, ns)

    def py(self, code: str, *args: str, limit: float = LIMIT_S, ns: str | None = None
           ) -> Result:
        return self.run([sys.executable, "-c", code, *args], limit, ns)

    def setup(self, *args: str, ok: tuple[int, ...] = (0,), limit: float = SETUP_LIMIT_S
              ) -> Result:
        """A preparing command (not under test): its failure is ``setup failed``."""
        r = run_command([sys.executable, "-m", "evomotion.cli", *args], self.tmp, self.env,
                        limit, self._logs())
        if r.returncode not in ok or r.hang:
            tail = (r.stderr.strip().splitlines() or [f"exit {r.returncode}"])[-1]
            raise SetupError(f"{' '.join(args[:2])}: {tail}"[:70])
        return r

    # -- mounts (tmpfs: a full or read-only disk)
    def tmpfs(self, rel: str, size: str = "64k", ro: bool = False) -> Path:
        if os.geteuid() != 0:
            raise SetupError("skipped: tmpfs mounts need root")
        p = self.tmp / rel
        p.mkdir(parents=True, exist_ok=True)
        opts = f"size={size}" + (",ro" if ro else "")
        subprocess.run(["mount", "-t", "tmpfs", "-o", opts, "hostile", str(p)], check=True)
        self.mounts.append(p)
        return p

    def remount(self, p: Path, opts: str) -> None:
        subprocess.run(["mount", "-o", f"remount,{opts}", str(p)], check=True)

    def close(self) -> None:
        for p in reversed(self.mounts):
            subprocess.run(["umount", "-l", str(p)], capture_output=True)
        self.mounts.clear()

    # -- the outcome
    def touched(self) -> list[str]:
        if self.before is None:
            return []
        after = snapshot(self.tmp, self.allow)
        diff = sorted(k for k in set(self.before) | set(after)
                      if self.before.get(k) != after.get(k))
        return diff


def worst(verdicts: list[str]) -> str:
    def rank(v: str) -> int:
        for i, w in enumerate(ORDER):
            if v.startswith(w):
                return i
        return len(ORDER)
    return min(verdicts, key=rank) if verdicts else "ok"


def is_good(v: str) -> bool:
    return v.split(" (")[0] in GOOD


def expect_error(r: Result, quick_s: float | None = None) -> str:
    """A refusal: one ``error:`` line, non-zero exit, no traceback (``quick_s``: and within
    that many seconds, else ``LATE``: the check came after the work)."""
    if r.hang:
        return "HANG"
    if "Traceback" in r.stderr:
        return "TRACEBACK"
    if r.returncode == 0:
        return "SILENT"
    if r.returncode < 0:
        return f"exit {r.returncode} (killed by signal {-r.returncode})"
    errs = r.error_lines()
    if len(errs) != 1:
        usage = "No such option" in r.stderr or "No such command" in r.stderr
        return "n/a (no such option/command)" if usage else f"exit {r.returncode}"
    if quick_s is not None and r.wall > quick_s:
        return f"LATE ({r.wall:.1f} s)"
    return "one-line error"


def expect_ok(r: Result, good: bool, why: str = "") -> str:
    """A command that should succeed, and ``good``: its result checked."""
    if r.hang:
        return "HANG"
    if "Traceback" in r.stderr:
        return "TRACEBACK"
    if r.returncode != 0:
        errs = r.error_lines()
        usage = "No such option" in r.stderr or "No such command" in r.stderr
        if usage:
            return "n/a (no such option/command)"
        return f"FAILED ({(errs[-1][7:] if errs else f'exit {r.returncode}')[:48]})"
    return "ok" if good else f"SILENT ({why})" if why else "SILENT"


def q(path: Path | str) -> str:
    """A path as a TOML string literal (for ``--set key=...``)."""
    return "'" + str(path) + "'"


def shell(*a: str) -> str:
    return " ".join(shlex.quote(x) for x in a)
