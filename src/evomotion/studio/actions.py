"""What the studio changes: start, stop and resume runs, each a normal ``evomotion`` process.

A run started here is exactly ``evomotion run STUDY [--preset P] --set KEY=VALUE ... --out DIR``
in its own process (so it is identical to the same command typed in a terminal, and survives
the studio). The studio makes the folder, marks it as a run folder
(:func:`evomotion.outfile.write_marker`, naming ``studio-stderr.txt``: the run loop refuses a
folder holding files no run wrote) and sends the process's stderr to ``studio-stderr.txt``
there (a failure before the run loop starts is seen there); a resume appends to it and
records it as the run's (:func:`evomotion.outfile.claim`).

Stop sends SIGTERM, which the run loop treats as Ctrl-C (checkpoint, log ``stopped:
interrupted``), through :func:`evomotion.run.lock.signal_owner`: only to a live process that
verifiably is that run (same host and boot, same start time, an ``evomotion`` command line),
never to a pid <= 1, a stale lock's reused pid or another host's process.
"""

from __future__ import annotations

import dataclasses
import json
import os
import re
import signal
import subprocess
import sys
import time
import types
import typing
from pathlib import Path
from typing import Any

from evomotion.errors import InputError
from evomotion.studio.data import is_resumable, resolve_run, run_status
from evomotion.studio.readers import head_tail, one_line

STDERR_NAME = "studio-stderr.txt"


def _spawn(args: list[str], run_dir: Path) -> subprocess.Popen:
    """``evomotion ARGS`` in its own session, its stderr appended to the run folder's
    :data:`STDERR_NAME` (a regular file only: never a FIFO or a device), which is recorded
    in the folder's marker as the run's."""
    from evomotion.outfile import claim, open_append

    err = open_append(run_dir / STDERR_NAME, "studio stderr file", binary=True)
    try:
        claim(run_dir / STDERR_NAME)  # a no-op where the marker names it already
        env = dict(os.environ)
        return subprocess.Popen([sys.executable, "-m", "evomotion.cli", *args],
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=err, start_new_session=True, env=env)
    except OSError as e:
        raise InputError(f"cannot start evomotion ({one_line(e)})") from None
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
    from evomotion.studies import study_with_preset

    s, preset = study_with_preset(study, preset)  # as `evomotion run` resolves them
    return resolve_config(s, None, sets, preset=preset)


def new_run_dir(root: Path, study: str) -> Path:
    stamp = time.strftime("%Y%m%d-%H%M%S")
    path, n = Path(root) / f"{study}-{stamp}", 1
    while path.exists():
        n += 1
        path = Path(root) / f"{study}-{stamp}-{n}"
    return path


#: a run name the user gives (the run folder's name below the runs folder)
RUN_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,79}$")


def check_run_name(root: Path, name: str) -> None:
    """One :class:`InputError` line for a name that is not a plain folder name or is taken."""
    if not RUN_NAME.match(name):
        raise InputError(f"run name {one_line(name, 40)!r}: expected 1-80 letters, digits, "
                         "'.', '_' or '-', starting with a letter or digit")
    if os.path.lexists(Path(root) / name):
        raise InputError(f"run name {name!r}: {Path(root) / name} exists already")


def make_run_folder(root: Path, study: str, name: str = "") -> Path:
    """A new folder ``ROOT/NAME`` (or ``ROOT/STUDY-STAMP[-N]``) marked as a run folder of
    ``study`` that names :data:`STDERR_NAME` as the run's (made here, never one that
    exists)."""
    from evomotion.outfile import WriteError, reason, write_marker

    if name:
        check_run_name(root, name)
    for _ in range(1 if name else 1000):
        out = Path(root) / name if name else new_run_dir(root, study)
        try:
            out.mkdir()
        except FileExistsError:
            if name:
                raise InputError(f"run name {name!r}: {out} exists already") from None
            continue  # taken meanwhile (another studio, the same second)
        except OSError as e:
            raise WriteError(f"{out}: cannot create the run folder ({reason(e)})") from None
        try:
            write_marker(out, study, [STDERR_NAME])
        except OSError as e:
            raise WriteError(f"{out}: cannot mark the run folder ({reason(e)})") from None
        return out
    raise WriteError(f"{root}: no free name for a new run folder of {study}")


def start_run(root: Path, study: str, preset: str | None, sets: list[str],
              name: str = "", tags: tuple[str, ...] = ()) -> tuple[Path, Any]:
    """Check the settings (one-line error), then start the run in ``ROOT/name`` (or a
    stamped folder) with ``tags`` (:mod:`.tags`); ``(run folder, process)``."""
    from evomotion.studies import study_with_preset
    from evomotion.studio.tags import check_tags, write_tags

    s, preset = study_with_preset(study, preset)  # a preset that is another study: that one
    study = s.name
    check_new_run(study, preset, sets)
    tags = check_tags(tags)
    out = make_run_folder(root, study, name)  # checks the name before making anything
    if tags:
        write_tags(out, tags)
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
            _, tail = head_tail(out / STDERR_NAME, 4096)
            text = tail.strip().splitlines()
            raise InputError(one_line(text[-1]) if text
                             else f"the run exited with {proc.returncode}")
        time.sleep(0.05)


def stop_run(root: Path, name: str) -> int:
    """SIGTERM to the run's process (a Ctrl-C stop that checkpoints) if it verifiably is
    that run (:func:`evomotion.run.lock.signal_owner`); its pid. Anything else (no lock, a
    stale lock, another host, pid <= 1, a lock that is not one) is one :class:`InputError`
    line and no signal is sent."""
    from evomotion.run.lock import signal_owner

    run_dir = resolve_run(root, name)
    try:
        return signal_owner(run_dir, signal.SIGTERM)
    except InputError as e:
        raise InputError(one_line(e)) from None
    except (OSError, ValueError, OverflowError) as e:
        raise InputError(f"{one_line(name, 120)}: no signal sent ({one_line(e)})") from None


def resume_run(root: Path, name: str) -> Any:
    """``evomotion resume RUN`` in its own process, for an interrupted run (or one whose lock
    is stale: killed) with checkpoints; its stderr is appended to :data:`STDERR_NAME`, which
    is recorded as the run's."""
    run_dir = resolve_run(root, name)
    status, _, _ = run_status(run_dir)
    if not is_resumable(run_dir, status):
        raise InputError(f"{one_line(name, 120)}: only an interrupted run with checkpoints can "
                         f"be resumed (this one is {status})")
    return _spawn(["resume", str(run_dir), "--quiet"], run_dir)


def extend_run(root: Path, name: str, generations: int) -> Any:
    """``evomotion resume RUN --set run.generations=N``: a finished (or interrupted) run with
    checkpoints goes on to ``generations``, more than it was set to run."""
    from evomotion.studio.data import read_config

    run_dir = resolve_run(root, name)
    status, _, _ = run_status(run_dir)
    if status != "finished" and not is_resumable(run_dir, status):
        raise InputError(f"{one_line(name, 120)}: only a finished or interrupted run with "
                         f"checkpoints can be extended (this one is {status})")
    if not any((run_dir / "checkpoints").glob("gen-*.json")):
        raise InputError(f"{one_line(name, 120)}: no checkpoint to extend from")
    run = read_config(run_dir)[1].get("run", {})
    now = run.get("generations", 0) if isinstance(run, dict) else 0
    if not isinstance(generations, int) or isinstance(generations, bool) or \
            not isinstance(now, int) or generations <= now:
        raise InputError(f"generations: expected a whole number above the run's {now}, got "
                         f"{generations!r}")
    return _spawn(["resume", str(run_dir), "--set", f"run.generations={generations}",
                   "--quiet"], run_dir)


# --- the new-run form: fields from the study's config schema ------------------------------


@dataclasses.dataclass(frozen=True)
class FormField:
    key: str  # section.name
    kind: str  # bool | int | float | str | text
    value: str  # the resolved value as the CLI would write it after --set
    doc: str = ""  # the field's comment in its dataclass (units, ranges)
    shown: str = ""  # what the field shows (floats shortened; studio/form_schema.py)
    choices: tuple[str, ...] = ()  # a registry's names, when the key is checked against one
    free: bool = False  # other values than ``choices`` allowed (a robot spec file)
    common: bool = True  # in the form's first group (else "advanced")


def _kind(tp: Any) -> str:
    """bool | int | float | str | text (anything else, written as a TOML literal)."""
    args = [a for a in typing.get_args(tp) if a is not type(None)]
    if typing.get_origin(tp) in (typing.Union, types.UnionType) and len(args) == 1:
        tp = args[0]
    return {bool: "bool", int: "int", float: "float", str: "str"}.get(tp, "text")


def robot_sets(study: str, robot: str | None) -> list[str]:
    """The ``--set`` naming ``robot`` (gym: the environment; the study's ``defaults_key``),
    none for no robot."""
    from evomotion.studies import get_study

    return [f"problem.{get_study(study).defaults_key}={json.dumps(robot)}"] if robot else []


def form_fields(study: str, preset: str | None = None, algorithm: str | None = None,
                robot: str | None = None) -> list[FormField]:
    """One field per key of ``[run]``, ``[algorithm]`` and ``[problem]`` with the value the
    study resolves to under ``preset`` (and ``algorithm.name``, and ``problem.robot``: a
    robot with defaults of its own, ``Study.robot_defaults``, shows them; gym: the
    environment, ``Study.defaults_key``)."""
    from evomotion.studies import get_study
    from evomotion.studio import form_schema as fs

    sets = [f"algorithm.name={algorithm!r}"] if algorithm else []
    sets += robot_sets(study, robot)
    cfg = check_new_run(study, preset, sets)
    common = fs.common_keys(get_study(study))
    out = []
    for sec in ("run", "algorithm", "problem"):
        obj = getattr(cfg, sec)
        cls: type = type(obj)  # (typed: a class is hashable, for field_docs' cache)
        hints = typing.get_type_hints(cls)
        docs = fs.field_docs(cls)
        for f in dataclasses.fields(obj):
            if sec == "algorithm" and f.name == "name":
                continue
            key, kind, v = f"{sec}.{f.name}", _kind(hints[f.name]), getattr(obj, f.name)
            opts = fs.choices(key)
            out.append(FormField(key, kind, v if kind == "str" and isinstance(v, str)
                                 else fs.toml_text(v), docs.get(f.name, ""),
                                 fs.shown_text(kind, v), tuple(opts[0]) if opts else (),
                                 bool(opts and opts[1]), key in common))
    return out


def changed_sets(fields: list[FormField], values: dict[str, str],
                 algorithm: str | None = None) -> list[str]:
    """``--set`` items for the fields whose text differs from what the form showed."""
    sets = [f"algorithm.name={algorithm!r}"] if algorithm else []
    for f in fields:
        shown = f.shown or f.value
        v = str(values.get(f.key, shown)).strip()
        if v != shown:
            sets.append(f"{f.key}={json.dumps(v) if f.kind == 'str' else v}")
    return sets


def form_errors(study: str, preset: str | None, sets: list[str],
                keys: list[str]) -> dict[str | None, str]:
    """Every error of the filled form at once, by the key it belongs to (None: the form's)."""
    from evomotion.studio.form_schema import all_errors

    return all_errors(lambda s: check_new_run(study, preset, s), sets, keys)
