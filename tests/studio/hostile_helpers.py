"""Hostile run folders and locks for the studio's issue-31 tests (each test makes its own)."""

from __future__ import annotations

import json
import os
import socket
from importlib import resources
from pathlib import Path

from evomotion.run.lock import boot_id, process_start

SHOOT = resources.files("evomotion.sim.robots.nao") / "motions" / "Shoot.motion"


def fake_run(root: Path, name: str, study: str = "functions", robot: str | None = None) -> Path:
    d = root / name
    d.mkdir(parents=True)
    extra = f'\n[problem]\nrobot = "{robot}"\n' if robot is not None else "\n"
    (d / "config.toml").write_text(f'study = "{study}"\n{extra}')
    (d / "stats.csv").write_text("generation,evaluations,best_so_far,wall_s\n0,10,3.5,0.1\n")
    (d / "log.txt").write_text("run x\nstopped: generations at generation 0\n")
    return d


def hostile_root(root: Path) -> Path:
    """A folder of runs, each hostile in its own way (what the outside tester tried, and the
    same classes of fault in the studio's other files)."""
    fake_run(root, "fine")
    d = fake_run(root, "fifo-log")  # the outside tester's case
    (d / "log.txt").unlink()
    os.mkfifo(d / "log.txt")
    d = fake_run(root, "fifo-everything")
    for name in ("stats.csv", "log.txt", "run.lock"):
        (d / name).unlink(missing_ok=True)
        os.mkfifo(d / name)
    d = root / "fifo-config"
    d.mkdir()
    os.mkfifo(d / "config.toml")
    d = fake_run(root, "device-links")
    for name in ("stats.csv", "log.txt", "run.lock", "best_kicks.json"):
        (d / name).unlink(missing_ok=True)
        os.symlink("/dev/zero", d / name)
    d = fake_run(root, "huge-sparse")
    for name in ("stats.csv", "log.txt", "population.bin", "archive.npz"):
        with open(d / name, "ab") as fh:
            fh.truncate(8 << 30)  # 8 GiB of holes: no disk used
    for robot in ("/dev/zero", "fifo-robot.toml", "huge-robot.toml", "/etc", "nao\0x"):
        safe = robot.strip("/").replace("/", "-").replace("\0", "NUL") or "root"
        d = fake_run(root, f"robot-{safe}", "humanoid-step", robot.replace("\0", "\\u0000"))
        (d / "best.motion").write_bytes(SHOOT.read_bytes())
    os.mkfifo(root / "fifo-robot.toml")
    with open(root / "huge-robot.toml", "ab") as fh:
        fh.truncate(4 << 30)
    return root


def finished_run(root, name="r"):
    """A run folder as a finished run leaves it (what the status and stop read)."""
    d = root / name
    d.mkdir(parents=True)
    (d / "config.toml").write_text('study = "functions"\n')
    (d / "stats.csv").write_text("generation,evaluations,best_so_far,wall_s\n0,10,3.5,0.1\n")
    (d / "log.txt").write_text("run functions seed 0\nstopped: generations at generation 0\n")
    (d / "checkpoints").mkdir()
    return d


def json_lock(pid, host=None, start=None, command="evomotion"):
    return json.dumps({"pid": pid, "host": socket.gethostname() if host is None else host,
                       "start": start, "boot": boot_id(), "command": command}) + "\n"


def stale_locks(pid):
    """Locks naming ``pid`` that do not name the run: a wrong start time, the older format,
    another host (both formats)."""
    start = process_start(pid)
    return {"wrong-start": json_lock(pid, start=(start or 0) + 12345),
            "right-start-not-evomotion": json_lock(pid, start=start),
            "old-format": f"pid {pid} on {socket.gethostname()}\n",
            "other-host": json_lock(pid, host="another-host.example", start=start),
            "other-host-old-format": f"pid {pid} on another-host.example\n"}
