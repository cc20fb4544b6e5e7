"""What the studio changes: start, stop and resume runs, each a normal ``evomotion`` process.

A run started here is exactly ``evomotion run STUDY [--preset P] --set KEY=VALUE ... --out DIR``
in its own process (so it is identical to the same command typed in a terminal, and survives
the studio); stop sends the run SIGTERM, which the run loop treats as Ctrl-C (checkpoint, log
``stopped: interrupted``); resume runs ``evomotion resume DIR``. The process's own stderr goes
to ``studio-stderr.txt`` in the run folder (a failure before the run loop starts is seen there).
"""

from __future__ import annotations

import dataclasses
import json
import os
import signal
import subprocess
import sys
import time
import types
import typing
from pathlib import Path
from typing import Any

from evomotion.errors import InputError
from evomotion.studio.data import lock_owner, resolve_run, run_status

STDERR_NAME = "studio-stderr.txt"


def _spawn(args: list[str], run_dir: Path) -> subprocess.Popen:
    run_dir.mkdir(parents=True, exist_ok=True)
    err = open(run_dir / STDERR_NAME, "ab")  # noqa: SIM115 - handed to the child
    try:
        env = dict(os.environ)
        return subprocess.Popen([sys.executable, "-m", "evomotion.cli", *args],
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=err, start_new_session=True, env=env)
    finally:
        err.close()


def run_command(study: str, preset: str | None, sets: list[str], out: Path) -> list[str]:
    """The ``evomotion`` arguments of a new run (what the page shows and starts)."""
    args = ["run", study]
    if preset:
        args += ["--preset", preset]
    for item in sets:
        args += ["--set", item]
    return args + ["--out", str(out), "--quiet"]


def check_new_run(study: str, preset: str | None, sets: list[str]) -> Any:
    """The resolved config, or the CLI's one-line :class:`InputError`."""
    from evomotion.run.config import resolve_config
    from evomotion.studies import get_study

    return resolve_config(get_study(study), None, sets, preset=preset)


def new_run_dir(root: Path, study: str) -> Path:
    stamp = time.strftime("%Y%m%d-%H%M%S")
    path, n = Path(root) / f"{study}-{stamp}", 1
    while path.exists():
        n += 1
        path = Path(root) / f"{study}-{stamp}-{n}"
    return path


def start_run(root: Path, study: str, preset: str | None, sets: list[str]) -> tuple[Path, Any]:
    """Check the settings (one-line error), then start the run; ``(run folder, process)``."""
    check_new_run(study, preset, sets)
    out = new_run_dir(root, study)
    proc = _spawn(run_command(study, preset, sets, out), out)
    _await_start(proc, out)
    return out, proc


def _await_start(proc: subprocess.Popen, out: Path, timeout_s: float = 60.0) -> None:
    """Wait until the run wrote its config.toml (its page can open), or report its error."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end and not (out / "config.toml").exists():
        if proc.poll() is not None:
            if (out / "config.toml").exists():
                return
            text = (out / STDERR_NAME).read_text(errors="replace").strip().splitlines()
            raise InputError(text[-1] if text else f"the run exited with {proc.returncode}")
        time.sleep(0.05)


def stop_run(root: Path, name: str) -> int:
    """SIGTERM to the run's process (a Ctrl-C stop that checkpoints); its pid."""
    run_dir = resolve_run(root, name)
    pid, alive = lock_owner(run_dir)
    if pid is None or not alive:
        raise InputError(f"{name}: the run is not running")
    os.kill(pid, signal.SIGTERM)
    return pid


def resume_run(root: Path, name: str) -> Any:
    run_dir = resolve_run(root, name)
    status, _, _ = run_status(run_dir)
    if status != "interrupted" or not (run_dir / "checkpoints").is_dir():
        raise InputError(f"{name}: only an interrupted run with checkpoints can be resumed "
                         f"(this one is {status})")
    return _spawn(["resume", str(run_dir), "--quiet"], run_dir)


# --- the new-run form: fields from the study's config schema ------------------------------


@dataclasses.dataclass(frozen=True)
class FormField:
    key: str  # section.name
    kind: str  # bool | int | float | str | text
    value: str  # the resolved value as the CLI would write it after --set
    doc: str = ""


def _text(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return v
    if v is None:
        return "none"
    if isinstance(v, tuple | list):
        return "[" + ", ".join(_text(x) if not isinstance(x, str) else repr(x) for x in v) + "]"
    return repr(v)


def _kind(tp: Any) -> str:
    """bool | int | float | str | text (anything else, written as a TOML literal)."""
    args = [a for a in typing.get_args(tp) if a is not type(None)]
    if typing.get_origin(tp) in (typing.Union, types.UnionType) and len(args) == 1:
        tp = args[0]
    return {bool: "bool", int: "int", float: "float", str: "str"}.get(tp, "text")


def form_fields(study: str, preset: str | None = None,
                algorithm: str | None = None) -> list[FormField]:
    """One field per key of ``[run]``, ``[algorithm]`` and ``[problem]`` with the value the
    study resolves to under ``preset`` (and ``algorithm.name``)."""
    sets = [f"algorithm.name={algorithm!r}"] if algorithm else []
    cfg = check_new_run(study, preset, sets)
    out = []
    for sec in ("run", "algorithm", "problem"):
        obj = getattr(cfg, sec)
        hints = typing.get_type_hints(type(obj))
        for f in dataclasses.fields(obj):
            if sec == "algorithm" and f.name == "name":
                continue
            out.append(FormField(f"{sec}.{f.name}", _kind(hints[f.name]),
                                 _text(getattr(obj, f.name))))
    return out


def changed_sets(fields: list[FormField], values: dict[str, str],
                 algorithm: str | None = None) -> list[str]:
    """``--set`` items for the values that differ from the form's defaults."""
    sets = [f"algorithm.name={algorithm!r}"] if algorithm else []
    for f in fields:
        v = values.get(f.key, f.value)
        v = str(v).strip()
        if v != f.value:
            sets.append(f"{f.key}={json.dumps(v) if f.kind == 'str' else v}")
    return sets


def field_of_error(message: str, keys: list[str]) -> str | None:
    """The form key a one-line error names (longest match), if any."""
    hits = [k for k in keys if k in message]
    return max(hits, key=len) if hits else None
