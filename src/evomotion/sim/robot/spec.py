"""The robot description: an MJCF file plus a small TOML spec, read and checked line by line.

```toml
[robot]
name = "dm-humanoid"
mjcf = "dm_control:suite/humanoid.xml"  # a path relative to this file, "evomotion:<path in the
                                         # package>" or "dm_control:<path in dm_control>"
torso = "torso"          # the body with the free joint (falls, heading, displacement)
floor = "floor"          # the floor geom
clearance_m = 0.0005     # lowest foot geom this far above the floor at the start
remove = ["ball"]        # bodies of the MJCF the robot does not need (optional)

[feet]                   # foot bodies in order (a biped: left, right); their geoms are the soles
left = "left_foot"
right = "right_foot"

[soles]                  # optional: the MJCF's own sole sites (on the foot bodies); the initial
left = "l_sole_site"     # state then puts the lowest of them clearance_m above the floor (else
right = "r_sole_site"    # a site is added at the centre of each foot's collision geoms)

[fall]
height_m = 0.8           # fallen: torso origin lower than this (m) ...
tilt_rad = 0.785         # ... or its up axis tilted more than this (rad)

[servo]                  # only when the MJCF drives joints with motors: position servos replace
kp = 300.0               # them (N m/rad), edited in with mujoco.MjSpec
kv = 10.0                # N m s/rad
force = "gear"           # |torque| <= the motor's gear x ctrlrange, or a number (N m)

[pose]                   # initial joint angles (rad); joints not named start at 0 (or keyframe)
right_knee = -0.3

[evolve]                 # the joints a study evolves and their ranges (rad)
right_hip_y = [-0.9, 0.2]

[gait]                   # the walk study's joint-space gait: channels by role, one per leg
kind = "biped"           # biped (left, right) | quadruped (front left, front right, hind
hip_pitch = ["-left_hip_y", "-right_hip_y"]   # left, hind right); "-": the joint's negative
knee = ["-left_knee", "-right_knee"]          # direction is the role's positive one
ankle_pitch = ["left_ankle_y", "right_ankle_y"]
```

A *channel* is an actuated joint (named by the joint) or, for an actuator on a tendon, the
actuator's name; ``[pose]``, ``[evolve]`` and ``[gait]`` name channels.

:func:`read_spec` returns a :class:`RobotSpec`; every mistake is a one-line
:class:`~evomotion.errors.InputError` ``FILE:LINE: what was expected``. The checks against the
model (unknown joint, range outside the model's limits, no sole geoms, motors without a
``[servo]``) are in :mod:`.build`.
"""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from evomotion.errors import InputError

SECTIONS = {
    "robot": {"name", "mjcf", "torso", "floor", "clearance_m", "keyframe", "remove"},
    "feet": None,  # free keys: foot name -> body
    "soles": None,  # foot name -> a site of the MJCF on that foot (optional)
    "fall": {"height_m", "tilt_rad"},
    "servo": {"kp", "kv", "force"},
    "pose": None,  # joint -> angle
    "evolve": None,  # joint -> [lo, hi]
    "gait": None,  # kind + role -> channels (the walk study's joint-space gait)
}
#: the walk study's gait roles per kind: required, optional; each lists one channel per leg
#: (biped: left, right; quadruped: front left, front right, hind left, hind right), a
#: leading "-" where the role's positive direction is the joint's negative one
GAIT_ROLES = {
    "biped": (("hip_pitch", "knee", "ankle_pitch"), ("hip_roll", "ankle_roll")),
    "quadruped": (("swing", "lift"), ("extend",)),
}
LEGS = {"biped": 2, "quadruped": 4}


@dataclass(frozen=True)
class RobotSpec:
    """A parsed robot spec; ``lines`` maps ``(section, key)`` to its line in ``path``."""

    path: Path
    name: str
    mjcf: str
    torso: str
    floor: str = "floor"
    clearance_m: float = 0.0005
    keyframe: str | None = None
    feet: dict[str, str] = field(default_factory=dict)
    soles: dict[str, str] = field(default_factory=dict)
    fall_height_m: float = 0.0
    fall_tilt_rad: float = math.pi / 4
    servo: dict[str, Any] | None = None
    pose: dict[str, float] = field(default_factory=dict)
    evolve: dict[str, tuple[float, float]] = field(default_factory=dict)
    remove: tuple[str, ...] = ()
    gait_kind: str | None = None
    gait: dict[str, tuple[str, ...]] = field(default_factory=dict)
    lines: dict[tuple[str, str], int] = field(default_factory=dict, compare=False)

    def where(self, section: str, key: str | None = None) -> str:
        """``FILE:LINE`` of ``[section] key`` (of the section header without ``key``)."""
        line = self.lines.get((section, key or ""), self.lines.get((section, ""), 0))
        return f"{self.path}:{line}" if line else str(self.path)

    def error(self, section: str, key: str | None, message: str) -> InputError:
        name = f"[{section}] {key}" if key else f"[{section}]"
        return InputError(f"{self.where(section, key)}: {name}: {message}")


def key_lines(text: str) -> dict[tuple[str, str], int]:
    """``(section, key) -> line`` of a flat TOML file (``(section, "")``: the header)."""
    out: dict[tuple[str, str], int] = {}
    section = ""
    for i, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        m = re.match(r"^\[\s*([A-Za-z0-9_.-]+)\s*\]", line)
        if m:
            section = m.group(1)
            out.setdefault((section, ""), i)
            continue
        m = re.match(r'^("?)([A-Za-z0-9_.-]+)\1\s*=', line)
        if m:
            out.setdefault((section, m.group(2)), i)
    return out


def _number(spec_path: Path, lines, section: str, key: str, value: Any, lo: float | None = None,
            lo_open: bool = False) -> float:
    where = f"{spec_path}:{lines.get((section, key), lines.get((section, ''), 0))}"
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InputError(f"{where}: [{section}] {key}: expected a finite number, got {value!r}")
    if lo is not None and (value < lo or (lo_open and value == lo)):
        raise InputError(f"{where}: [{section}] {key}: expected a number "
                         f"{'>' if lo_open else '>='} {lo}, got {value!r}")
    return float(value)


def read_spec(path: str | Path) -> RobotSpec:
    """Parse and check the robot spec at ``path`` (structure and values; the model is checked
    when it is built)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"{path}: no such robot spec") from None
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"{path}: cannot read the robot spec ({e})") from None
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"{path}: not valid TOML ({e})") from None
    lines = key_lines(text)

    def where(section: str, key: str = "") -> str:
        return f"{path}:{lines.get((section, key), lines.get((section, ''), 0))}"

    for section, value in raw.items():
        if section not in SECTIONS:
            raise InputError(f"{where(section)}: unknown section [{section}]; valid: "
                             f"{', '.join(SECTIONS)}")
        if not isinstance(value, dict):
            raise InputError(f"{where(section)}: [{section}] must be a table")
        allowed = SECTIONS[section]
        for key in value:
            if allowed is not None and key not in allowed:
                raise InputError(f"{where(section, key)}: [{section}] unknown key {key!r}; "
                                 f"valid: {', '.join(sorted(allowed))}")
    robot = raw.get("robot")
    if robot is None:
        raise InputError(f"{path}: missing section [robot] (name, mjcf, torso)")
    for key in ("name", "mjcf", "torso"):
        if not isinstance(robot.get(key), str) or not robot.get(key):
            raise InputError(f"{where('robot', key) if key in robot else where('robot')}: "
                             f"[robot] {key}: expected a non-empty string")
    feet = raw.get("feet", {})
    if not feet:
        raise InputError(f"{where('feet') if 'feet' in raw else path}: [feet]: expected the "
                         "foot bodies, e.g. left = \"l_foot\" and right = \"r_foot\"")
    for key, body in feet.items():
        if not isinstance(body, str) or not body:
            raise InputError(f"{where('feet', key)}: [feet] {key}: expected a body name")
    soles = raw.get("soles", {})
    for key, site in soles.items():
        if key not in feet:
            raise InputError(f"{where('soles', key)}: [soles] {key}: not a foot of [feet] "
                             f"({', '.join(feet)})")
        if not isinstance(site, str) or not site:
            raise InputError(f"{where('soles', key)}: [soles] {key}: expected a site name")
    if soles and set(soles) != set(feet):
        missing = sorted(set(feet) - set(soles))[0]
        raise InputError(f"{where('soles')}: [soles]: expected a site for every foot, "
                         f"missing {missing!r}")
    fall = raw.get("fall", {})
    if "height_m" not in fall:
        raise InputError(f"{where('fall') if 'fall' in raw else path}: [fall] height_m: "
                         "expected the torso height (m) below which the robot has fallen")
    height = _number(path, lines, "fall", "height_m", fall["height_m"], 0.0, lo_open=True)
    tilt = _number(path, lines, "fall", "tilt_rad", fall.get("tilt_rad", math.pi / 4), 0.0,
                   lo_open=True)
    if tilt > math.pi:
        raise InputError(f"{where('fall', 'tilt_rad')}: [fall] tilt_rad: expected at most pi "
                         f"(3.1416), got {tilt}")
    servo = raw.get("servo")
    if servo is not None:
        if "kp" not in servo:
            raise InputError(f"{where('servo')}: [servo] kp: expected the servos' stiffness "
                             "(N m/rad)")
        servo = dict(servo)
        servo["kp"] = _number(path, lines, "servo", "kp", servo["kp"], 0.0, lo_open=True)
        servo["kv"] = _number(path, lines, "servo", "kv", servo.get("kv", 0.0), 0.0)
        force = servo.get("force", "gear")
        if force != "gear":
            force = _number(path, lines, "servo", "force", force, 0.0, lo_open=True)
        servo["force"] = force
    pose = {k: _number(path, lines, "pose", k, v) for k, v in raw.get("pose", {}).items()}
    evolve = {}
    for key, value in raw.get("evolve", {}).items():
        if not (isinstance(value, list) and len(value) == 2):
            raise InputError(f"{where('evolve', key)}: [evolve] {key}: expected [lo, hi] (rad)")
        lo, hi = (_number(path, lines, "evolve", key, v) for v in value)
        if not lo < hi:
            raise InputError(f"{where('evolve', key)}: [evolve] {key}: expected lo < hi, got "
                             f"{value}")
        evolve[key] = (lo, hi)
    clearance = _number(path, lines, "robot", "clearance_m", robot.get("clearance_m", 0.0005),
                        0.0)
    floor = robot.get("floor", "floor")
    keyframe = robot.get("keyframe")
    for key, value in (("floor", floor), ("keyframe", keyframe)):
        if value is not None and not isinstance(value, str):
            raise InputError(f"{where('robot', key)}: [robot] {key}: expected a name")
    remove = robot.get("remove", [])
    if not (isinstance(remove, list) and all(isinstance(b, str) for b in remove)):
        raise InputError(f"{where('robot', 'remove')}: [robot] remove: expected a list of body "
                         "names")
    kind, roles = _gait(raw.get("gait"), where)
    return RobotSpec(path, robot["name"], robot["mjcf"], robot["torso"], floor, clearance,
                     keyframe, dict(feet), dict(soles), height, tilt, servo, pose, evolve,
                     tuple(remove), kind, roles, lines)


def _gait(gait: dict | None, where) -> tuple[str | None, dict[str, tuple[str, ...]]]:
    """(kind, role -> channels) of a ``[gait]`` section (see :data:`GAIT_ROLES`)."""
    if gait is None:
        return None, {}
    kind = gait.get("kind")
    if kind not in GAIT_ROLES:
        raise InputError(f"{where('gait', 'kind')}: [gait] kind: expected one of "
                         f"{', '.join(GAIT_ROLES)}, got {kind!r}")
    required, optional = GAIT_ROLES[kind]
    roles = {}
    for key, value in gait.items():
        if key == "kind":
            continue
        if key not in required + optional:
            raise InputError(f"{where('gait', key)}: [gait] unknown role {key!r} for a {kind}; "
                             f"valid: {', '.join(required + optional)}")
        if not (isinstance(value, list) and len(value) == LEGS[kind]
                and all(isinstance(v, str) and v.lstrip("-") for v in value)):
            raise InputError(f"{where('gait', key)}: [gait] {key}: expected {LEGS[kind]} "
                             "channel names (one per leg, '-' in front to flip the sign)")
        roles[key] = tuple(value)
    missing = [r for r in required if r not in roles]
    if missing:
        raise InputError(f"{where('gait')}: [gait] missing role {missing[0]!r} (a {kind} "
                         f"needs {', '.join(required)})")
    return kind, roles
