"""Issue 31, class 3: every command that writes a path the user names, with that path a
device (``/dev/null``, in a private ``/dev``; and a symlink to it), a FIFO, a socket, a folder,
in a missing folder (no traceback, no silent mkdir), on a read-only file system or a full one
(tmpfs mounts). A refusal must come before the command's work: its time is compared with the
control (the same command writing a new file), ``LATE`` past half of it. A full disk must leave
no partial file. Runs into a full or read-only disk: one line, then ``evomotion resume``
completes once there is room (ok).
"""

from __future__ import annotations

import errno
import os
import socket

from hostile_cases_31 import FN, MOTIONS, fixture, sets, short_motion
from hostile_harness import Box, Result, expect_error, expect_ok

#: the control's wall time per (tree, command): a refusal past half of it is LATE
CONTROL: dict[tuple[str, str], float] = {}
DEVNULL = "character special file 1:3"


def _export(flag):
    return lambda b, p: ["export", str(MOTIONS / "TurnRight40.motion"), flag, p]


COMMANDS = {  # name: (argv(box, path), extension, fixtures, output is a folder)
    "export --naoqi": (_export("--naoqi"), ".py", (), False),
    "export --json": (_export("--json"), ".json", (), False),
    "replay --video": (lambda b, p: ["replay", str(short_motion(b)), "--json", "--hold", "0",
                                     "--video", p], ".mp4", (), False),
    "walk-to --out": (lambda b, p: ["humanoid-repertoire", "walk-to", "rep", "--x", "0.1",
                                    "--json", "--out", p], ".motion", ("rep",), False),
    "walk-to --video": (lambda b, p: ["humanoid-repertoire", "walk-to", "rep", "--x", "0.1",
                                      "--json", "--out", "w.motion", "--video", p], ".mp4",
                        ("rep",), False),
    "quadruped simulate --video": (lambda b, p: ["quadruped-plan", "simulate", "plan", "--json",
                                                 "--video", p], ".mp4", ("plan",), False),
    "biped-kick plan --out": (lambda b, p: ["biped-kick", "plan", "--out", p], ".png", (),
                              False),
    "biped-kick play --video": (lambda b, p: ["biped-kick", "play", "--json", "--video", p],
                                ".mp4", (), False),
    "plot --out": (lambda b, p: ["plot", "fn", "--out", p.removesuffix(".png")], ".png",
                   ("fn",), False),
    "grid-path make-map": (lambda b, p: ["grid-path", "make-map", p], ".map", (), False),
    "quadruped missions --json": (lambda b, p: [
        "quadruped-plan", "missions", "--seeds", "1", "--worlds", "corridor", "--rule-sets",
        "B", "--heuristics", "analytic", "--json", p], ".json", (), False),
    "humanoid-step study --out": (lambda b, p: ["humanoid-step", "study", "--quick", "--out",
                                                p], "", (), True),
    "biped-kick study --out": (lambda b, p: ["biped-kick", "study", "--seeds", "1", "--budget",
                                             "8", "--kicks", "2", "--out", p], "", (), True),
}
#: the work is long (a video, a study): no full-disk case (it would time out legitimately)
LONG = {"walk-to --video", "biped-kick play --video", "quadruped simulate --video",
        "quadruped missions --json", "humanoid-step study --out", "biped-kick study --out"}
TARGETS = ("FIFO", "socket", "folder", "missing folder", "read-only fs", "full disk",
           "symlink to /dev/null", "/dev/null")


def _socket(path) -> None:
    s = socket.socket(socket.AF_UNIX)
    s.bind(str(path))
    s.close()


def _fill(path) -> None:
    """Fill the tmpfs at ``path`` to the last byte."""
    fd = os.open(path / "filler", os.O_WRONLY | os.O_CREAT, 0o644)
    try:
        while True:
            os.write(fd, b"\0" * 4096)
    except OSError as e:
        if e.errno != errno.ENOSPC:
            raise
    finally:
        os.close(fd)


def _devnull(r: Result) -> str | None:
    """TOUCHED when the private /dev/null is no longer the null device (no report: the
    command was killed, HANG says so)."""
    kind = r.extra.get("devnull")
    if kind is None or kind == DEVNULL or (kind == "no report" and r.hang):
        return None
    return f"TOUCHED (/dev/null became: {kind})"


def _late(b: Box, cmd: str, r: Result) -> str | None:
    ref = CONTROL.get((b.label, cmd))
    if ref is not None and ref > 4.0 and r.wall > 0.5 * ref:
        return f"LATE ({r.wall:.1f} s, the work takes {ref:.1f} s)"
    return None


def control(cmd: str):
    argv, ext, fixtures, folder = COMMANDS[cmd]

    def case(b: Box) -> str:
        for f in fixtures:
            fixture(b, f)
        b.allow = ["new" + ext, "new.svg", "w.motion", *fixtures]
        r = b.cli(*argv(b, "new" + ext), limit=120)
        CONTROL[(b.label, cmd)] = r.wall
        p = b.tmp / ("new" + ext)
        good = p.is_dir() if folder else p.is_file() and p.stat().st_size > 0
        if cmd == "quadruped simulate --video" and r.returncode == 1 and \
                '"body_up": false' in r.stdout:
            r.returncode = 0  # exit 1: the body fell (documented); the video is the check
        return expect_ok(r, good, "no output written")
    return case


def write_case(cmd: str, target: str):
    argv, ext, fixtures, folder = COMMANDS[cmd]

    def case(b: Box) -> str:
        for f in fixtures:
            fixture(b, f)
        b.allow = ["w.motion"]
        ns = None
        name = "out" + ext
        paths = [b.tmp / name] + ([b.tmp / "out.svg"] if cmd == "plot --out" else [])
        if target == "FIFO":
            for p in paths:
                os.mkfifo(p)
        elif target == "socket":
            for p in paths:
                _socket(p)
        elif target == "folder":
            for p in paths:
                p.mkdir()
        elif target == "missing folder":
            name = f"missing/{name}"
            b.allow.append("missing")  # judged below: a made folder is SILENT
        elif target == "read-only fs":
            b.tmpfs("ro", "1m", ro=True)
            name = f"ro/{name}"
        elif target == "full disk":
            _fill(b.tmpfs("full", "64k"))
            b.allow.append("full")
            name = f"full/{name}"
        elif target == "symlink to /dev/null":
            ns = "dev"
            for p in paths:
                os.symlink("/dev/null", p)
        elif target == "/dev/null":
            ns = "dev"
            name = "/dev/null" + (".png" if cmd == "plot --out" else "")
        if not name.startswith(("/", "missing/", "ro/", "full/")):
            b.allow += [p.name for p in paths]  # the named path itself: judged below
        r = b.cli(*argv(b, name), ns=ns)
        touched = _devnull(r)
        if touched:
            return touched
        if target == "missing folder" and (b.tmp / "missing").exists():
            return "SILENT (made the missing folder)" if r.returncode == 0 else \
                f"{expect_error(r)} (made the missing folder)"
        if target == "full disk":
            left = sorted(set(os.listdir(b.tmp / "full")) - {"filler"})
            if left:
                return f"FAILED (left in the full disk: {', '.join(left)[:30]})"
            return expect_error(r)
        return expect_error(r)
    return case


def _late_wrap(cmd: str, inner):
    def case(b: Box) -> str:
        v = inner(b)
        last = b.results[-1] if b.results else None
        if v == "one-line error" and last is not None:
            return _late(b, cmd, last) or v
        return v
    return case


def study_out(cmd: str, target: str):
    """A study writing a results folder: into a FIFO, a file, the project folder, /dev/null,
    a missing folder."""
    argv, _, _, _ = COMMANDS[cmd]

    def case(b: Box) -> str:
        ns, name = None, "out"
        if target == "FIFO":
            os.mkfifo(b.tmp / "out")
            b.allow = ["out"]  # the named path itself: judged below
        elif target == "existing file":
            name = "outside/keep.txt"
            b.allow = [name]
        elif target == "project folder":
            name = "project"
        elif target == "missing folder":
            name = "missing/out"
        elif target == "/dev/null":
            ns, name = "dev", "/dev/null"
        r = b.cli(*argv(b, name), ns=ns)
        touched = _devnull(r)
        if touched:
            return touched
        if target == "missing folder" and (b.tmp / "missing").exists():
            return "SILENT (made the missing folder)"
        v = expect_error(r)
        return (_late(b, cmd, r) or v) if v == "one-line error" else v
    return case


def run_full_then_resume(b: Box) -> str:
    """A run into a disk that fills: one line; with room again, resume completes."""
    disk = b.tmpfs("disk", "160k")
    b.allow = ["disk"]
    r = b.cli("run", "functions", "-q", "--out", "disk/run", *sets(
        "problem.dim=4", "algorithm.pop_size=20", "run.generations=400",
        "run.checkpoint_every=10", "run.history_every=1"), limit=60)
    v1 = expect_error(r)
    if v1 != "one-line error":
        return v1 if r.returncode else "SILENT (the run fit: disk not full)"
    b.remount(disk, "size=64m")
    r2 = b.cli("resume", "disk/run", "-q", limit=60)
    stats = b.tmp / "disk/run/stats.csv"
    rows = stats.read_text().splitlines() if stats.is_file() else []
    gens = [ln.split(",")[0] for ln in rows[1:]]
    return expect_ok(r2, gens == [str(g) for g in range(401)], f"{len(gens)} rows")


def run_readonly_then_resume(b: Box) -> str:
    """A finished run on a disk made read-only: resume is one line; made writable: ok."""
    disk = b.tmpfs("disk", "16m")
    b.allow = ["disk"]
    b.setup("run", "functions", "-q", "--out", "disk/run", *FN, "--set", "run.checkpoint_every=1")
    b.remount(disk, "ro")
    r = b.cli("resume", "disk/run", "-q", "--set", "run.generations=6")
    v1 = expect_error(r)
    if v1 != "one-line error":
        return v1
    b.remount(disk, "rw")
    r2 = b.cli("resume", "disk/run", "-q", "--set", "run.generations=6")
    rows = (b.tmp / "disk/run/stats.csv").read_text().splitlines()
    return expect_ok(r2, len(rows) == 8, f"{len(rows) - 1} rows")


def run_readonly_new(b: Box) -> str:
    b.tmpfs("ro", "1m", ro=True)
    return expect_error(b.cli("run", "functions", "-q", "--out", "ro/run", *FN))


def cases() -> dict:
    out, last = {}, {}
    for cmd in COMMANDS:
        folder = COMMANDS[cmd][3]
        out[f"W {cmd} -> a new file (control)"] = control(cmd)
        if folder:
            for t in ("FIFO", "existing file", "project folder", "missing folder"):
                out[f"W {cmd} -> {t}"] = study_out(cmd, t)
            last[f"W {cmd} -> /dev/null (private /dev)"] = study_out(cmd, "/dev/null")
            continue
        for t in TARGETS:
            if t == "full disk" and cmd in LONG:
                continue
            if cmd == "plot --out" and t == "/dev/null":
                continue  # a stem: /dev/null.png is a new name (the symlink case covers it)
            name = f"W {cmd} -> {t}" + (" (private /dev)" if "/dev/null" in t else "")
            fn = _late_wrap(cmd, write_case(cmd, t))
            (last if "/dev/null" in t else out)[name] = fn
    out["W run into a disk that fills, then resume with room"] = run_full_then_resume
    out["W resume on a read-only disk, then writable again"] = run_readonly_then_resume
    out["W run --out on a read-only file system"] = run_readonly_new
    return out, last
