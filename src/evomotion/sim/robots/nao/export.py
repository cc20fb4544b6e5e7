"""Exports of a motion for a real NAO: a NAOqi Python script and a JSON keyframe file.

Both are written only after the real-robot checks of :mod:`.joint_limits` (NAO H25 V5 ranges,
V3.x motor speeds between keyframes, one hip yaw-pitch motor), and only to the path named.

NAOqi script (Python 2.7, as the NAO's SDK, or 3): ``python OUT.py [--ip 127.0.0.1]
[--port 9559] [--speed 0.2] [--rest]``. It connects with ``naoqi.ALProxy("ALMotion", ip,
port)``, calls ``wakeUp()``, goes to the first pose with ``angleInterpolationWithSpeed(names,
angles, speed)`` (each joint's first given value; a fraction of the maximum speed), then plays
the motion with ONE blocking ``angleInterpolation(names, angleLists, timeLists, True)``
(NAOqi ``ALMotion`` joint control API, ``doc.aldebaran.com/1-14/naoqi/motion/
control-joint-api.html``): per joint the keyframes where the motion gives it a value (``*``
skipped), times in seconds from the call, i.e. ``t - t_first``; keyframes at ``t_first`` are
the first pose, so a joint given only there is held and left out of the call. ALMotion
interpolates between a joint's keyframes, as Webots' player does linearly. ``rest()`` at the
end only with ``--rest``.

Keyframe file: ``{"format": "evomotion-keyframes/1", "joints": [...], "times_s": [...],
"angles_rad": {joint: [angle or null, ...]}, "source": "..."}`` (``null`` = ``*``; times and
angles as the motion's, shortest exact float text, so :func:`read_keyframes` gives them back).
"""

from __future__ import annotations

import json
import math
import os
import stat
from pathlib import Path

import numpy as np

from evomotion.errors import FileFormatError, InputError
from evomotion.outfile import WriteError, atomic_write_text, check_target, reason
from evomotion.sim.motion import MAX_MOTION_MS, NAO_JOINT_NAMES, Motion, read_motion
from evomotion.sim.robots.nao.joint_limits import check_motion
from evomotion.textio import decode_utf8, loads_json, read_file_bytes

FORMAT = "evomotion-keyframes/1"
MAX_KEYFRAMES_BYTES = 16 * 1024 * 1024
MAX_KEYFRAMES_DEPTH = 4  # {"angles_rad": {joint: [..]}}
_KEYS = ("format", "joints", "times_s", "angles_rad", "source")


def _floats(values: np.ndarray | list[float]) -> str:
    return "[" + ", ".join(repr(float(v)) for v in values) + "]"


def naoqi_plan(motion: Motion) -> tuple[list[str], list[float], list[str], list[list[float]],
                                         list[list[float]]]:
    """(first-pose names, first-pose angles, names, angleLists, timeLists) of the script."""
    t0 = int(motion.times_ms[0])
    first_names, first_angles, names, angles, times = [], [], [], [], []
    for j, name in enumerate(motion.joints):
        col = motion.values[:, j]
        given = np.nonzero(~np.isnan(col))[0]
        if given.size == 0:
            continue
        first_names.append(name)
        first_angles.append(float(col[given[0]]))
        later = [k for k in given if motion.times_ms[k] > t0]
        if later:
            names.append(name)
            angles.append([float(col[k]) for k in later])
            times.append([(int(motion.times_ms[k]) - t0) / 1000.0 for k in later])
    return first_names, first_angles, names, angles, times


def naoqi_script(motion: Motion, source: str = "motion") -> str:
    """The text of the NAOqi Python script that plays ``motion`` (see the module doc)."""
    first_names, first_angles, names, angles, times = naoqi_plan(motion)
    duration = (int(motion.times_ms[-1]) - int(motion.times_ms[0])) / 1000.0
    rows_a = "".join(f"    {_floats(a)},  # {n}\n" for n, a in zip(names, angles, strict=True))
    rows_t = "".join(f"    {_floats(t)},  # {n}\n" for n, t in zip(names, times, strict=True))
    src = json.dumps(str(source), ensure_ascii=True)
    return f'''#!/usr/bin/env python
# -*- coding: utf-8 -*-
"""Play a motion on a real NAO through NAOqi ALMotion (written by evomotion export).

Usage: python THIS.py [--ip 127.0.0.1] [--port 9559] [--speed 0.2] [--rest]

Wakes the robot up, goes to the first pose with angleInterpolationWithSpeed (SPEED of the
maximum joint speed), plays the motion ({duration:.3f} s) with one angleInterpolation call
(times in seconds from the call, angles in radians) and rests only with --rest. Checked
before export against the NAO H25 V5 joint ranges and the V3.x motor speeds. Stand the robot
on the floor, clear of obstacles, with someone ready to catch it.
"""
from __future__ import print_function

import argparse
import sys

SOURCE = {src}
DURATION_S = {duration!r}
FIRST_NAMES = {json.dumps(first_names)}
FIRST_ANGLES = {_floats(first_angles)}
NAMES = {json.dumps(names)}
ANGLES = [
{rows_a}]
TIMES = [
{rows_t}]


def main(argv=None):
    parser = argparse.ArgumentParser(description="Play %s on a NAO through ALMotion." % SOURCE)
    parser.add_argument("--ip", default="127.0.0.1", help="the robot's address (127.0.0.1)")
    parser.add_argument("--port", type=int, default=9559, help="the NAOqi port (9559)")
    parser.add_argument("--speed", type=float, default=0.2,
                        help="fraction of the maximum speed for the first pose (0.2)")
    parser.add_argument("--rest", action="store_true", help="rest at the end")
    args = parser.parse_args(argv)
    if not 0.0 < args.speed <= 1.0:
        parser.error("--speed must be in (0, 1]")
    try:
        import naoqi
    except ImportError:
        print("error: no module naoqi (install the NAOqi Python SDK)", file=sys.stderr)
        return 1
    motion = naoqi.ALProxy("ALMotion", args.ip, args.port)
    motion.wakeUp()
    motion.angleInterpolationWithSpeed(FIRST_NAMES, FIRST_ANGLES, args.speed)
    if NAMES:
        motion.angleInterpolation(NAMES, ANGLES, TIMES, True)
    if args.rest:
        motion.rest()
    return 0


if __name__ == "__main__":
    sys.exit(main())
'''


def keyframes_json(motion: Motion, source: str = "motion") -> str:
    """The text of the JSON keyframe file of ``motion`` (one line per joint)."""
    def angle_list(col: np.ndarray) -> str:
        return "[" + ", ".join("null" if np.isnan(v) else repr(float(v)) for v in col) + "]"

    rows = ",\n".join(f"    {json.dumps(n)}: {angle_list(motion.values[:, j])}"
                      for j, n in enumerate(motion.joints))
    times = _floats(np.asarray(motion.times_ms) / 1000.0)
    return (f'{{\n  "format": {json.dumps(FORMAT)},\n  "joints": {json.dumps(list(motion.joints))},'
            f'\n  "times_s": {times},\n  "angles_rad": {{\n{rows}\n  }},\n'
            f'  "source": {json.dumps(str(source))}\n}}\n')


def _number(v: object) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def parse_keyframes(text: str, path: str | Path = "<keyframes>") -> tuple[Motion, str]:
    """(motion, source) from the text of a keyframe file; bad input raises a one-line
    :class:`FileFormatError` naming ``path``."""
    def bad(what: str, line: int | None = None) -> FileFormatError:
        return FileFormatError(path, line, what)

    data = loads_json(text, path, max_depth=MAX_KEYFRAMES_DEPTH)
    if not isinstance(data, dict):
        raise bad("expected a JSON object")
    extra = sorted(set(data) - set(_KEYS))
    if extra:
        raise bad(f"unexpected key {extra[0]!r}; expected {', '.join(_KEYS)}")
    if data.get("format") != FORMAT:
        raise bad(f"expected \"format\": \"{FORMAT}\"")
    joints, times, angles = data.get("joints"), data.get("times_s"), data.get("angles_rad")
    source = data.get("source", "")
    if not isinstance(source, str):
        raise bad("expected \"source\" to be a string")
    if not isinstance(joints, list) or not joints or not all(isinstance(n, str) for n in joints):
        raise bad("expected \"joints\": a non-empty list of joint names")
    unknown = [n for n in joints if n not in NAO_JOINT_NAMES]
    if unknown:
        raise bad(f"unknown joint {unknown[0]!r}; expected a NAO joint name")
    if len(set(joints)) != len(joints):
        raise bad("expected each joint name once")
    if not isinstance(times, list) or not times or not all(_number(t) for t in times):
        raise bad("expected \"times_s\": a non-empty list of finite numbers")
    if any(not 0 <= t <= MAX_MOTION_MS / 1000 for t in times):
        raise bad(f"expected times in whole milliseconds from 0 to {MAX_MOTION_MS // 1000} s")
    ms = [round(t * 1000) for t in times]
    if any(abs(t * 1000 - m) > 1e-6 or m < 0 or m > MAX_MOTION_MS for t, m in zip(times, ms)):
        raise bad(f"expected times in whole milliseconds from 0 to {MAX_MOTION_MS // 1000} s")
    if any(b <= a for a, b in zip(ms, ms[1:])):
        raise bad("expected strictly increasing times")
    if not isinstance(angles, dict) or set(angles) != set(joints):
        raise bad("expected \"angles_rad\": one list per joint of \"joints\"")
    cols = []
    for n in joints:
        col = angles[n]
        if not isinstance(col, list) or len(col) != len(times):
            raise bad(f"expected {len(times)} angles for {n}")
        if not all(v is None or _number(v) for v in col):
            raise bad(f"expected finite numbers or null as angles of {n}")
        cols.append([np.nan if v is None else float(v) for v in col])
    return Motion(tuple(joints), np.array(ms), np.array(cols).T), source


def read_keyframes(path: str | Path) -> tuple[Motion, str]:
    """(motion, source) of a keyframe file written by :func:`write_keyframes`."""
    data = read_file_bytes(path, "keyframe file", MAX_KEYFRAMES_BYTES)
    return parse_keyframes(decode_utf8(data, path), path)


def _out_path(path: str | Path, what: str) -> Path:
    """``path`` checked as an output (:func:`evomotion.outfile.check_target`: a new name or a
    regular file in an existing folder, never a device, FIFO or folder)."""
    return check_target(path, what)


def write_naoqi(path: str | Path, motion: Motion, source: str = "motion") -> Path:
    """Write the NAOqi script atomically (no checks: see :func:`export_motion`)."""
    return atomic_write_text(_out_path(path, "NAOqi script"), naoqi_script(motion, source),
                             "NAOqi script")


def write_keyframes(path: str | Path, motion: Motion, source: str = "motion") -> Path:
    """Write the JSON keyframe file atomically (no checks: see :func:`export_motion`)."""
    return atomic_write_text(_out_path(path, "keyframe file"), keyframes_json(motion, source),
                             "keyframe file")


def export_motion(motion: Motion, *, naoqi: str | Path | None = None,
                  json_path: str | Path | None = None, clip: bool = False,
                  speed_margin: float = 1.0, source: str = "motion") -> list[str]:
    """Check ``motion`` (:func:`~.joint_limits.check_motion`), then write the outputs named;
    returns one line per thing done. Nothing is written when a check fails."""
    if naoqi is None and json_path is None:
        raise InputError("export: expected at least one output (--naoqi OUT.py, --json OUT.json)")
    outs = [Path(p) for p in (naoqi, json_path) if p is not None]
    if len(outs) == 2 and outs[0].resolve() == outs[1].resolve():
        raise InputError(f"export: --naoqi and --json name the same file {outs[0]}")
    if naoqi is not None:  # before any work: a device or a missing folder is one line
        _out_path(naoqi, "NAOqi script (--naoqi)")
    if json_path is not None:
        _out_path(json_path, "keyframe file (--json)")
    motion, clipped = check_motion(motion, clip=clip, speed_margin=speed_margin)
    done = [f"clipped {clipped} angle{'s' if clipped != 1 else ''} to the NAO H25 V5 joint "
            "ranges"] if clip else []
    what = (f"{len(motion.joints)} joints, {len(motion.times_ms)} keyframes, "
            f"{motion.duration_s - motion.times_ms[0] / 1000:.3f} s")
    if naoqi is not None:
        done.append(f"wrote {write_naoqi(naoqi, motion, source)} (NAOqi script; {what})")
    if json_path is not None:
        done.append(f"wrote {write_keyframes(json_path, motion, source)} (keyframes; {what})")
    return done


def write_run_exports(motion: Motion, out_dir: Path, log, source: str = "best.motion") -> bool:
    """A run's ``best_naoqi.py`` and ``best_keyframes.json`` in ``out_dir`` when ``motion``
    passes the real-NAO checks; otherwise the reason goes to ``log`` (one line), nothing is
    written and exports of an earlier best are removed (the run does not fail for it)."""
    names = ("best_naoqi.py", "best_keyframes.json")
    try:
        export_motion(motion, naoqi=out_dir / names[0], json_path=out_dir / names[1],
                      source=source)
    except WriteError:
        raise  # a full disk, say: the run ends unfinished (resumable), not silently
    except InputError as exc:
        for name in names:
            _remove_regular(out_dir / name)
        log(f"best_naoqi.py and best_keyframes.json not written: {exc}")
        return False
    log("best_naoqi.py and best_keyframes.json written (checked against a real NAO's "
        "joint ranges and motor speeds)")
    return True


def _remove_regular(path: Path) -> None:
    """Remove ``path`` when it is a regular file (a device or FIFO there is left alone)."""
    try:
        if stat.S_ISREG(os.lstat(path).st_mode):
            path.unlink()
    except FileNotFoundError:
        pass
    except OSError as e:
        raise WriteError(f"{path}: cannot remove the stale export ({reason(e)})") from None


def export_command(motion_path: Path, naoqi: Path | None, json_path: Path | None,
                   clip: bool, speed_margin: float) -> list[str]:
    """``evomotion export``: read a Webots .motion, check it, write the outputs."""
    outs = [Path(p).resolve() for p in (naoqi, json_path) if p is not None]
    if Path(motion_path).resolve() in outs:
        raise InputError(f"export: an output would overwrite the input {motion_path}")
    motion = read_motion(motion_path)
    return export_motion(motion, naoqi=naoqi, json_path=json_path, clip=clip,
                         speed_margin=speed_margin, source=Path(motion_path).name)
