"""Robots described by an MJCF file and a TOML spec (``--robot FILE.toml`` or a bundled name).

- :mod:`.spec`: the spec format, read with line-numbered errors;
- :mod:`.build`: the robot built from it with ``mujoco.MjSpec`` (position servos in place of
  motors, sole sites and sensors) and checked against the model.

Bundled specs (``specs/``): ``nao`` (the NAO H25, the humanoid studies' default robot),
``dm-humanoid`` and ``dm-quadruped`` (the dm_control suite's models, shipped in the
``dm-control`` wheel: extra ``[robots]``), ``op3`` (ROBOTIS OP3, authored in
``sim/models/op3`` from published data).
"""

from __future__ import annotations

from pathlib import Path

from evomotion.errors import InputError
from evomotion.sim.robot.build import Robot, build_robot
from evomotion.sim.robot.spec import RobotSpec, read_spec

SPECS_DIR = Path(__file__).resolve().parent / "specs"


def bundled_specs() -> list[str]:
    """Names of the bundled robot specs."""
    return sorted(p.stem for p in SPECS_DIR.glob("*.toml"))


def spec_path(name_or_path: str) -> Path:
    """The spec file of a bundled name or a path; a one-line error for neither. A bundled
    name (``nao``, ``op3``, ...) means the bundled spec even where the working directory holds
    a file or folder of that name (``evomotion run ... --out nao``)."""
    path = Path(name_or_path)
    bundled = SPECS_DIR / f"{name_or_path}.toml"
    if path.suffix != ".toml" and len(path.parts) == 1 and bundled.is_file():
        return bundled  # a bundled name wins over a file or folder of that name here
    if path.suffix == ".toml" or path.exists():
        return path
    raise InputError(f"unknown robot {name_or_path!r}; bundled: {', '.join(bundled_specs())} "
                     "(or a path to a spec .toml)")


def is_nao(robot: str) -> bool:
    """Does a study's ``problem.robot`` name the NAO (the default "" or its bundled spec's
    name ``nao``)? A copy of ``nao.toml`` under another path is another robot."""
    return robot in ("", "nao")


def load_nao(robot: str, other: str) -> Robot:
    """The NAO of a NAO-only problem class; a one-line error naming ``other`` (the class
    for another robot) when ``robot`` is not the NAO."""
    if not is_nao(robot):
        raise InputError(f"problem.robot = {robot!r}: another robot's problem is built by "
                         f"make_problem(cfg) ({other})")
    return load_robot("nao")


_CACHE: dict[str, Robot] = {}  # key: path, mtime and size of the spec


def load_robot(name_or_path: str) -> Robot:
    """The robot of a bundled spec name or a spec file (built once per process and version
    of the file)."""
    path = spec_path(name_or_path)
    try:
        stat = path.stat()
        key = f"{path.resolve()}:{stat.st_mtime_ns}:{stat.st_size}"  # an edited spec reloads
    except OSError:
        key = str(path)
    if key not in _CACHE:
        _CACHE[key] = build_robot(read_spec(path))
    return _CACHE[key]


__all__ = ["Robot", "RobotSpec", "build_robot", "bundled_specs", "is_nao", "load_nao",
           "load_robot", "read_spec", "spec_path"]
