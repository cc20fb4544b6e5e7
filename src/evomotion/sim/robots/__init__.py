"""The robots: one folder per robot and the generic code that reads any robot's description.

Each robot is one folder ``sim/robots/<name>/`` (``-`` in a name is ``_`` in its folder), like
MuJoCo Playground's per-robot folders: its MJCF (or, for the dm_control suite's robots, the
spec's pointer into the ``dm-control`` wheel), its spec ``<name>.toml``, its constants and
any code of its own (the NAO's closed-form leg IK, motor-speed limits, Webots names, NAOqi
export), which the spec declares as optional *capabilities* (``[capabilities]``).

- :mod:`.spec`: the spec format, read with line-numbered errors;
- :mod:`.build`: the robot built from it with ``mujoco.MjSpec`` (position servos in place of
  motors, sole sites and sensors) and checked against the model;
- :mod:`.mjcf`: the MJCF and the files it names, read bounded; :mod:`.limits`: model checks.

Bundled robots: ``nao`` (the NAO H25, the humanoid studies' default robot), ``op3`` (ROBOTIS
OP3, authored in ``op3/`` from published data), ``dm-humanoid`` and ``dm-quadruped`` (the
dm_control suite's models, shipped in the ``dm-control`` wheel: extra ``[robots]``).
"""

from __future__ import annotations

from pathlib import Path

from evomotion.errors import InputError
from evomotion.sim.robots.build import Robot, build_robot
from evomotion.sim.robots.spec import CAPABILITIES, RobotSpec, read_spec

ROBOTS_DIR = Path(__file__).resolve().parent


def robot_folder(name: str) -> Path:
    """The folder of the bundled robot ``name`` (it may not exist)."""
    return ROBOTS_DIR / name.replace("-", "_")


def bundled_robots() -> list[str]:
    """Names of the bundled robots (the stems of ``<folder>/<name>.toml``)."""
    return sorted(p.stem for p in ROBOTS_DIR.glob("*/*.toml")
                  if p.parent.name == p.stem.replace("-", "_"))


def _bundled_spec(name: str) -> Path | None:
    if not name or "/" in name or "\\" in name or name.startswith("."):
        return None
    path = robot_folder(name) / f"{name}.toml"
    return path if path.is_file() else None


def spec_path(name_or_path: str) -> Path:
    """The spec file of a bundled name or a path; a one-line error for neither. A bundled
    name (``nao``, ``op3``, ...) means the bundled spec even where the working directory holds
    a file or folder of that name (``evomotion run ... --out nao``)."""
    path = Path(name_or_path)
    bundled = _bundled_spec(name_or_path)
    if path.suffix != ".toml" and len(path.parts) == 1 and bundled is not None:
        return bundled  # a bundled name wins over a file or folder of that name here
    if path.suffix == ".toml" or path.exists():
        return path
    raise InputError(f"unknown robot {name_or_path!r}; bundled: {', '.join(bundled_robots())} "
                     "(or a path to a spec .toml)")


def capability_modules(spec: RobotSpec) -> dict[str, str]:
    """``capability -> module`` of a spec's ``[capabilities]``, when the spec is the bundled
    one of its robot's folder (the modules are that folder's); a spec elsewhere (a copy of
    ``nao.toml``, a user's robot) has the description but not the code: none."""
    bundled = _bundled_spec(spec.name)
    try:
        same = bundled is not None and spec.path.resolve() == bundled.resolve()
    except OSError:
        same = False
    if not same:
        return {}
    package = f"{__name__}.{robot_folder(spec.name).name}"
    return {cap: f"{package}.{module}" for cap, module in spec.capabilities.items()}


_CACHE: dict[str, Robot] = {}  # key: path, mtime and size of the spec


def load_robot(name_or_path: str) -> Robot:
    """The robot of a bundled spec name or a spec file (built once per process and version
    of the file), with the capabilities of its folder's code when it is a bundled robot."""
    import dataclasses

    path = spec_path(name_or_path)
    try:
        stat = path.stat()
        key = f"{path.resolve()}:{stat.st_mtime_ns}:{stat.st_size}"  # an edited spec reloads
    except OSError:
        key = str(path)
    if key not in _CACHE:
        robot = build_robot(read_spec(path))
        _CACHE[key] = dataclasses.replace(robot, capabilities=capability_modules(robot.spec))
    return _CACHE[key]


def capabilities_of(name_or_path: str) -> dict[str, str]:
    """The capabilities of a robot named in a config (``""``: the NAO) from its spec alone
    (the model is not built); none for a spec that cannot be read."""
    try:
        return capability_modules(read_spec(spec_path(name_or_path or "nao")))
    except InputError:
        return {}


__all__ = ["CAPABILITIES", "ROBOTS_DIR", "Robot", "RobotSpec", "build_robot", "bundled_robots",
           "capabilities_of", "capability_modules", "load_robot", "read_spec",
           "robot_folder", "spec_path"]
