"""The robot description: an MJCF file plus a small TOML spec, read and checked line by line.

```toml
[robot]
name = "dm-humanoid"
mjcf = "dm_control:suite/humanoid.xml"  # a path inside this file's folder, "evomotion:<path in
                                         # the package>" or "dm_control:<path in dm_control>"
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
:class:`~evomotion.errors.InputError` ``FILE:LINE: what was expected``. The file is read with
a size limit (:data:`MAX_SPEC_BYTES`; a FIFO or a device is refused without blocking); every
number must be finite and within its physical range (:data:`RANGES`: ``clearance_m = 1e300``
is refused, not simulated), every name a printable one-line string. The checks against the
model (unknown joint, range outside the model's limits, no sole geoms, motors without a
``[servo]``) are in :mod:`.build`.
"""

from __future__ import annotations

import math
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from evomotion.errors import InputError
from evomotion.textio import decode_utf8, read_file_bytes

SECTIONS = {
    "robot": {"name", "mjcf", "torso", "floor", "clearance_m", "keyframe", "remove", "mass_kg"},
    "feet": None,  # free keys: foot name -> body
    "soles": None,  # foot name -> a site of the MJCF on that foot (optional)
    "fall": {"height_m", "tilt_rad"},
    "servo": {"kp", "kv", "force"},
    "pose": None,  # joint -> angle
    "evolve": None,  # joint -> [lo, hi]
    "gait": None,  # kind + role -> channels (the walk study's joint-space gait)
    "capabilities": None,  # capability -> module of the robot's folder (bundled robots)
}
#: the optional abilities a bundled robot's own code may add (``[capabilities]``: name =
#: the module of its folder that provides it); a study that needs one the robot lacks says so
CAPABILITIES = {
    "leg_ik": "a closed-form leg inverse kinematics",
    "speed_limits": "its motors' no-load speeds (motions checked against them)",
    "webots_names": "Webots/NAOqi joint names (Webots .motion files as the robot plays them)",
    "naoqi_export": "export of motions to NAOqi (a Python script for the real robot)",
    "naoqi_policy": "export of closed-loop policies to NAOqi (a runner script for the real "
                    "robot)",
    "mirror": "its left-right mirror of joints (mirror-symmetric policies)",
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
    #: the published total mass (kg; perturbed worlds scale pushes by it), else the model's
    mass_kg: float | None = None
    #: capability -> module of the robot's folder (see :data:`CAPABILITIES`)
    capabilities: dict[str, str] = field(default_factory=dict)
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


#: the largest spec file read (bytes)
MAX_SPEC_BYTES = 1 * 2**20
#: the most entries of a free section ([feet], [soles], [pose], [evolve], [gait]) or list
MAX_ENTRIES = {"feet": 16, "soles": 16, "pose": 1000, "evolve": 1000, "gait": 16,
               "remove": 1000, "capabilities": len(CAPABILITIES)}
MAX_NAME = 200  # characters of a name (a body, joint, site, ...)
MAX_ROBOT_NAME = 64
ANGLE_LIMIT = 2 * math.pi
#: the physical range of each number of a spec: (lowest, highest, unit, lowest excluded);
#: [pose] values and [evolve] bounds are joint angles within +-2 pi rad (m for a slide joint
#: or a tendon)
RANGES: dict[tuple[str, str], tuple[float, float, str, bool]] = {
    ("robot", "clearance_m"): (0.0, 0.1, "m", False),
    ("robot", "mass_kg"): (0.0, 1e4, "kg", True),
    ("fall", "height_m"): (0.0, 10.0, "m", True),
    ("fall", "tilt_rad"): (0.0, math.pi, "rad", True),
    ("servo", "kp"): (0.0, 1e5, "N m/rad", True),
    ("servo", "kv"): (0.0, 1e4, "N m s/rad", False),
    ("servo", "force"): (0.0, 1e4, "N m", True),
    ("pose", ""): (-ANGLE_LIMIT, ANGLE_LIMIT, "rad", False),
    ("evolve", ""): (-ANGLE_LIMIT, ANGLE_LIMIT, "rad", False),
}


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _number(spec_path: Path, lines, section: str, key: str, value: Any) -> float:
    """``value`` as a float when it is a finite number within the physical range of
    ``[section] key`` (:data:`RANGES`), else one line naming the file, line and key."""
    where = f"{spec_path}:{lines.get((section, key), lines.get((section, ''), 0))}"
    lo, hi, unit, lo_open = RANGES.get((section, key)) or RANGES[(section, "")]
    if isinstance(value, bool) or not isinstance(value, int | float) or (
            isinstance(value, float) and not math.isfinite(value)):
        raise InputError(f"{where}: [{section}] {key}: expected a finite number ({unit}), got "
                         f"{_short(value)}")
    if value < lo or value > hi or (lo_open and value == lo):
        shown = f"{value:.6g}" if isinstance(value, float) or abs(value) < 10**12 else \
            f"an integer of {len(str(abs(value)))} digits"
        raise InputError(f"{where}: [{section}] {key}: expected a number in "
                         f"{'(' if lo_open else '['}{lo:g}, {hi:g}] {unit}, got {shown}")
    return float(value)


def _check_name(where: str, label: str, value: Any, limit: int = MAX_NAME) -> None:
    """A name of the spec: a non-empty string of printable characters (no line breaks or
    control characters, which would forge lines in logs and messages), at most ``limit``."""
    if not isinstance(value, str) or not value:
        raise InputError(f"{where}: {label}: expected a non-empty string, got {_short(value)}")
    if len(value) > limit or not value.isprintable():
        raise InputError(f"{where}: {label}: expected at most {limit} printable characters "
                         f"(no line breaks or control characters), got {_short(value)}")


def read_spec(path: str | Path) -> RobotSpec:
    """Parse and check the robot spec at ``path`` (structure and values; the model is checked
    when it is built)."""
    path = Path(path)
    if not os.path.lexists(path):
        raise InputError(f"{path}: no such robot spec")
    text = decode_utf8(read_file_bytes(path, "robot spec", MAX_SPEC_BYTES), path)
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"{path}: not valid TOML ({_one_line(e)})") from None
    except (RecursionError, ValueError, MemoryError) as e:  # nested too deep, huge integer
        raise InputError(f"{path}: not valid TOML ({type(e).__name__}: "
                         f"{_one_line(e)[:80]})") from None
    lines = key_lines(text)

    def where(section: str, key: str = "") -> str:
        return f"{path}:{lines.get((section, key), lines.get((section, ''), 0))}"

    for section, value in raw.items():
        if section not in SECTIONS:
            raise InputError(f"{where(section)}: unknown section [{_short(section)[1:-1]}]; "
                             f"valid: {', '.join(SECTIONS)}")
        if not isinstance(value, dict):
            raise InputError(f"{where(section)}: [{section}] must be a table")
        allowed = SECTIONS[section]
        limit = MAX_ENTRIES.get(section)
        if limit is not None and len(value) > limit:
            raise InputError(f"{where(section)}: [{section}]: expected at most {limit} "
                             f"entries, got {len(value)}")
        for key in value:
            if allowed is not None and key not in allowed:
                raise InputError(f"{where(section, key)}: [{section}] unknown key "
                                 f"{_short(key)}; valid: {', '.join(sorted(allowed))}")
            _check_name(where(section, key), f"[{section}] key", key)
    robot = raw.get("robot")
    if robot is None:
        raise InputError(f"{path}: missing section [robot] (name, mjcf, torso)")
    for key in ("name", "mjcf", "torso"):
        if key not in robot:
            raise InputError(f"{where('robot')}: [robot] {key}: expected a non-empty string")
        _check_name(where("robot", key), f"[robot] {key}", robot[key],
                    MAX_ROBOT_NAME if key == "name" else MAX_NAME)
    feet = raw.get("feet", {})
    if not feet:
        raise InputError(f"{where('feet') if 'feet' in raw else path}: [feet]: expected the "
                         "foot bodies, e.g. left = \"l_foot\" and right = \"r_foot\"")
    for key, body in feet.items():
        _check_name(where("feet", key), f"[feet] {key}", body)
    soles = raw.get("soles", {})
    for key, site in soles.items():
        if key not in feet:
            raise InputError(f"{where('soles', key)}: [soles] {key}: not a foot of [feet] "
                             f"({', '.join(feet)})")
        _check_name(where("soles", key), f"[soles] {key}", site)
    if soles and set(soles) != set(feet):
        missing = sorted(set(feet) - set(soles))[0]
        raise InputError(f"{where('soles')}: [soles]: expected a site for every foot, "
                         f"missing {missing!r}")
    fall = raw.get("fall", {})
    if "height_m" not in fall:
        raise InputError(f"{where('fall') if 'fall' in raw else path}: [fall] height_m: "
                         "expected the torso height (m) below which the robot has fallen")
    height = _number(path, lines, "fall", "height_m", fall["height_m"])
    tilt = _number(path, lines, "fall", "tilt_rad", fall.get("tilt_rad", math.pi / 4))
    servo = raw.get("servo")
    if servo is not None:
        if "kp" not in servo:
            raise InputError(f"{where('servo')}: [servo] kp: expected the servos' stiffness "
                             "(N m/rad)")
        servo = dict(servo)
        servo["kp"] = _number(path, lines, "servo", "kp", servo["kp"])
        servo["kv"] = _number(path, lines, "servo", "kv", servo.get("kv", 0.0))
        force = servo.get("force", "gear")
        if force != "gear":
            force = _number(path, lines, "servo", "force", force)
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
    clearance = _number(path, lines, "robot", "clearance_m", robot.get("clearance_m", 0.0005))
    floor = robot.get("floor", "floor")
    keyframe = robot.get("keyframe")
    for key, value in (("floor", floor), ("keyframe", keyframe)):
        if value is not None:
            _check_name(where("robot", key), f"[robot] {key}", value)
    remove = robot.get("remove", [])
    if not isinstance(remove, list) or len(remove) > MAX_ENTRIES["remove"]:
        raise InputError(f"{where('robot', 'remove')}: [robot] remove: expected a list of at "
                         f"most {MAX_ENTRIES['remove']} body names")
    for body in remove:
        _check_name(where("robot", "remove"), "[robot] remove", body)
    kind, roles = _gait(raw.get("gait"), where)
    capabilities = _capabilities(raw.get("capabilities", {}), where)
    mass = robot.get("mass_kg")
    mass = None if mass is None else _number(path, lines, "robot", "mass_kg", mass)
    return RobotSpec(path, robot["name"], robot["mjcf"], robot["torso"], floor, clearance,
                     keyframe, dict(feet), dict(soles), height, tilt, servo, pose, evolve,
                     tuple(remove), kind, roles, mass, capabilities, lines)


def _capabilities(section: dict, where) -> dict[str, str]:
    """``[capabilities]``: known names (:data:`CAPABILITIES`) -> module names (identifiers)."""
    out = {}
    for key, module in section.items():
        if key not in CAPABILITIES:
            raise InputError(f"{where('capabilities', key)}: [capabilities] unknown capability "
                             f"{_short(key)}; valid: {', '.join(CAPABILITIES)}")
        if not (isinstance(module, str) and module.isidentifier()):
            raise InputError(f"{where('capabilities', key)}: [capabilities] {key}: expected "
                             f"the name of a module of the robot's folder, got {_short(module)}")
        out[key] = module
    return out


def _one_line(e: BaseException) -> str:
    return " ".join(str(e).split())


def _gait(gait: dict | None, where) -> tuple[str | None, dict[str, tuple[str, ...]]]:
    """(kind, role -> channels) of a ``[gait]`` section (see :data:`GAIT_ROLES`)."""
    if gait is None:
        return None, {}
    kind = gait.get("kind")
    if not isinstance(kind, str) or kind not in GAIT_ROLES:
        raise InputError(f"{where('gait', 'kind')}: [gait] kind: expected one of "
                         f"{', '.join(GAIT_ROLES)}, got {_short(kind)}")
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
        for v in value:
            _check_name(where("gait", key), f"[gait] {key}", v)
        roles[key] = tuple(value)
    missing = [r for r in required if r not in roles]
    if missing:
        raise InputError(f"{where('gait')}: [gait] missing role {missing[0]!r} (a {kind} "
                         f"needs {', '.join(required)})")
    return kind, roles
