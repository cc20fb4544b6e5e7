"""Webots ``.motion`` files: reader and writer.

Format (Webots ``src/controller/c/motion.c``, the parser the robot controller uses):

- line 1: ``#WEBOTS_MOTION,V1.0`` then the joint names, on the same line (current variant) or
  alone on line 2 (older variant, e.g. Webots' ``HandWave.motion``);
- each further line: ``time,poseName,v1,...,vN`` with ``time`` = ``[[MM:]SS:]mmm``
  (``MM*60000 + SS*1000 + mmm`` ms), strictly increasing; values in radians, ``*`` = unset
  (the joint is not commanded around that pose); an empty line ends the file;
- tokens are separated by commas (``strtok(",\\n\\r")``: CRLF is fine, empty fields collapse).

Bad input raises :class:`~evomotion.errors.FileFormatError` naming the file and line: bytes
that are not UTF-8, lines longer than :data:`MAX_LINE`, values that are not finite decimal
numbers (``nan``, ``inf``, ``1e999``), time stamps beyond :data:`MAX_MOTION_MS` (a motion is at
most 10 minutes long, so a replay never asks for more than that) and files larger than
:data:`MAX_MOTION_BYTES`.

A :class:`Motion` holds any robot's joints (``read_motion(path, robot.joints)``); without
``joints`` a file may name the NAO's (:data:`NAO_JOINT_NAMES`, Webots' names). Webots' own NAO
motions ship in the NAO's folder (:mod:`evomotion.sim.robots.nao.webots_motions`).
"""

from __future__ import annotations

import re
from collections.abc import Collection
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from evomotion.errors import FileFormatError
from evomotion.textio import decode_utf8, read_file_bytes, split_lines

#: Every NAO device name a motion may drive (the 22 modelled joints + wrists and hands).
NAO_JOINT_NAMES: frozenset[str] = frozenset((
    "HeadYaw", "HeadPitch",
    "LShoulderPitch", "LShoulderRoll", "LElbowYaw", "LElbowRoll", "LWristYaw", "LHand",
    "RShoulderPitch", "RShoulderRoll", "RElbowYaw", "RElbowRoll", "RWristYaw", "RHand",
    "LHipYawPitch", "LHipRoll", "LHipPitch", "LKneePitch", "LAnklePitch", "LAnkleRoll",
    "RHipYawPitch", "RHipRoll", "RHipPitch", "RKneePitch", "RAnklePitch", "RAnkleRoll",
))
MAGIC, VERSION = "#WEBOTS_MOTION", "V1.0"
MAX_LINE = 4095  # motion.c reads lines with fgets(buffer, 4096)
MAX_MOTION_MS = 10 * 60 * 1000  # the longest motion read: 10 minutes
MAX_MOTION_BYTES = 8 * 1024 * 1024  # a minute of 26 joints every 40 ms: about 1 MiB
_TIME = re.compile(r"^[0-9:]+$")
#: What ``sscanf("%lf")`` reads as a whole token, restricted to finite decimal numbers.
_NUMBER = re.compile(r"^[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?$")
_NUM = r"(?:\*|[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?)"
#: a row's values joined by commas, each ``*`` or a decimal number (checked in one match)
_ROW = re.compile(rf"{_NUM}(?:,{_NUM})*")
_SEP = re.compile("[,\r]")


@dataclass
class Motion:
    """Key poses: ``values[K, N]`` (rad, NaN = ``*``) of ``joints[N]`` at ``times_ms[K]``."""

    joints: tuple[str, ...]
    times_ms: np.ndarray
    values: np.ndarray
    pose_names: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.times_ms = np.asarray(self.times_ms, dtype=np.int64)
        self.values = np.asarray(self.values, dtype=float).reshape(len(self.times_ms), -1)
        if not self.pose_names:
            self.pose_names = [f"Pose{i + 1}" for i in range(len(self.times_ms))]

    @property
    def duration_s(self) -> float:
        return float(self.times_ms[-1]) / 1000.0

    def column(self, joint: str) -> np.ndarray:
        return self.values[:, self.joints.index(joint)]


def parse_time_ms(token: str) -> int | None:
    """``[[MM:]SS:]mmm`` -> milliseconds, or None when malformed."""
    if not _TIME.match(token):
        return None
    parts = token.split(":")
    if len(parts) > 3 or any(p == "" for p in parts):
        return None
    nums = [int(p) if len(p) <= 18 else 10**18 for p in parts]  # huge: beyond any maximum
    weights = (60000, 1000, 1)[-len(nums):]
    return sum(n * w for n, w in zip(nums, weights, strict=True))


def format_time_ms(ms: int) -> str:
    """Milliseconds -> ``MM:SS:mmm`` as Webots writes it."""
    ms = int(ms)
    return f"{ms // 60000:02d}:{ms // 1000 % 60:02d}:{ms % 1000:03d}"


def _tokens(line: str) -> list[str]:
    """``strtok(line, ",\\n\\r")``: empty fields collapse (blanks around a token are dropped)."""
    return [t for t in map(str.strip, _SEP.split(line)) if t]


def _value(token: str) -> float | None:
    """A value token: ``*`` -> NaN, a finite decimal number -> float, else None."""
    if token == "*":
        return np.nan
    if not _NUMBER.match(token):
        return None
    v = float(token)
    return v if np.isfinite(v) else None


def read_motion(path: str | Path, joints: Collection[str] | None = None) -> Motion:
    """Read a Webots ``.motion`` file (both header variants); ``joints``: the joint names
    it may use (default: the NAO's; another robot's channels, :mod:`evomotion.sim.robots`)."""
    path = Path(path)
    data = read_file_bytes(path, "motion file", MAX_MOTION_BYTES)
    return parse_motion(decode_utf8(data, path), path, joints)


def parse_motion(text: str, path: str | Path = "<motion>",
                 known: Collection[str] | None = None) -> Motion:
    """Parse the text of a ``.motion`` file; ``path`` names it in error messages; ``known``:
    the joint names it may use (default: the NAO's)."""
    path = Path(path)
    text = text.removeprefix("\ufeff")
    lines = split_lines(text)
    for lineno, line in enumerate(lines, start=1):
        if line.strip() == "" and lineno > 1:
            break  # an empty line ends the file: what follows is never read
        n = len(line) if line.isascii() else len(line.encode("utf-8"))
        if n > MAX_LINE:
            raise FileFormatError(path, lineno, f"expected lines of at most {MAX_LINE} bytes "
                                                f"(Webots reads 4096-byte lines), got {n}")
    if not lines:
        raise FileFormatError(path, 1, f"expected '{MAGIC},{VERSION}' header, got empty file")
    head = _tokens(lines[0])
    if len(head) < 2 or head[0] != MAGIC or head[1] != VERSION:
        raise FileFormatError(path, 1, f"expected '{MAGIC},{VERSION}' header")
    joints, first = head[2:], 1
    if not joints:  # older variant: the joint names on line 2
        joints = _tokens(lines[1]) if len(lines) > 1 else []
        first = 2
    if not joints:
        raise FileFormatError(path, first, "expected at least one joint name")
    for name in joints:
        if known is None and name not in NAO_JOINT_NAMES:
            raise FileFormatError(path, first, f"unknown joint {name!r}; expected a NAO joint name")
        if known is not None and name not in known:
            raise FileFormatError(path, first, f"unknown joint {name!r}; expected one of the "
                                  f"robot's: {', '.join(known)}")
    if len(set(joints)) != len(joints):
        raise FileFormatError(path, first, "expected each joint name once")
    times: list[int] = []
    names: list[str] = []
    rows: list[np.ndarray] = []
    for lineno, line in enumerate(lines[first:], start=first + 1):
        if line.strip() == "":
            break  # an empty line ends the file (motion.c)
        tok = _tokens(line)
        t = parse_time_ms(tok[0]) if tok else None
        if t is None:
            got = tok[0] if tok else line.strip()
            raise FileFormatError(path, lineno, f"bad time stamp {got!r}; expected MM:SS:mmm")
        if t > MAX_MOTION_MS:
            raise FileFormatError(path, lineno, f"expected a time stamp of at most "
                                  f"{format_time_ms(MAX_MOTION_MS)} (the maximum motion "
                                  f"duration, {MAX_MOTION_MS // 60000} minutes), got {tok[0]!r}")
        if times and t <= times[-1]:
            raise FileFormatError(path, lineno, "expected strictly increasing time stamps")
        if len(tok) - 2 != len(joints):
            raise FileFormatError(path, lineno,
                                  f"expected {len(joints)} values, got {max(len(tok) - 2, 0)}")
        values = tok[2:]
        row = None
        if _ROW.fullmatch(",".join(values)):  # the fast path: one match, floats in C
            row = np.fromiter(map(float, ("nan" if v == "*" else v for v in values)), float,
                              len(values))  # 8 bytes a value (a list of floats: 32)
        if row is None or np.isinf(row).any():
            for value in values:
                if _value(value) is None:
                    raise FileFormatError(path, lineno, f"bad value {value[:40]!r}; expected "
                                                        "a finite number or '*'")
        times.append(t)
        names.append(tok[1])
        if row is None:  # not reached: every value passed _value, so _ROW matched
            raise FileFormatError(path, lineno, "expected numbers or '*' separated by commas")
        rows.append(row)
    if not rows:
        raise FileFormatError(path, first + 1, "expected at least one pose")
    return Motion(tuple(joints), np.array(times), np.stack(rows), names)


def format_motion(motion: Motion, header_on_first_line: bool = True) -> str:
    """Text of a motion file. Values use Python's shortest exact float text (``*`` for NaN),
    so that :func:`read_motion` gives back exactly the same numbers."""
    if np.any(np.diff(motion.times_ms) <= 0):
        raise ValueError("motion times must be strictly increasing")
    sep = "," if header_on_first_line else "\n"
    out = [f"{MAGIC},{VERSION}{sep}{','.join(motion.joints)}"]
    for t, name, row in zip(motion.times_ms, motion.pose_names, motion.values, strict=True):
        vals = ",".join("*" if np.isnan(v) else repr(float(v)) for v in row)
        line = f"{format_time_ms(t)},{name},{vals}"
        if len(line) > MAX_LINE:
            raise ValueError(f"motion line longer than {MAX_LINE} characters")
        out.append(line)
    return "\n".join(out) + "\n"


def write_motion(path: str | Path, motion: Motion, header_on_first_line: bool = True,
                 what: str = "motion file", mkdir: bool = False) -> Path:
    """Write ``motion`` to ``path`` (``\\n`` line endings, no blank lines) atomically through
    :mod:`evomotion.outfile` (a device, FIFO or folder at ``path`` is refused, a missing folder
    too unless ``mkdir``; a failed write leaves no partial file)."""
    from evomotion.outfile import atomic_write_text

    text = format_motion(motion, header_on_first_line)
    return atomic_write_text(path, text, what, mkdir)
