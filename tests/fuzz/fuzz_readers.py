"""The file readers under test, by corpus folder, and what an accepted file must satisfy."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from evomotion.errors import FileFormatError, InputError
from evomotion.sim.motion import MAX_MOTION_MS, NAO_JOINT_NAMES, read_motion
from evomotion.studies.arm_ik.scenario import MAX_ABS, SCENARIO_DIR, load_scenario
from evomotion.studies.grid_path.maps import MAX_MAP_CELLS, read_map
from evomotion.studies.quadruped_plan.plans.checker import PlanViolationError, check_plan
from evomotion.studies.quadruped_plan.plans.plan import read_plan
from evomotion.studies.quadruped_plan.worlds.world import WORLD_DIR, read_world
from fixture_files import WEBOTS_MOTIONS

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "fuzz" / "data"
CORPUS = ROOT / "corpus"
WEBOTS = WEBOTS_MOTIONS
MAPS = ROOT.parent / "src" / "evomotion" / "studies" / "grid_path" / "maps"
SHOOT = ROOT.parent / "src" / "evomotion" / "sim" / "robots" / "nao" / "motions" / "Shoot.motion"


def check_motion(path: Path) -> None:
    m = read_motion(path)
    k, n = len(m.times_ms), len(m.joints)
    assert k >= 1 and n >= 1 and m.values.shape == (k, n) and len(m.pose_names) == k
    assert set(m.joints) <= NAO_JOINT_NAMES and len(set(m.joints)) == n
    assert np.all(np.diff(m.times_ms) > 0) and m.times_ms[0] >= 0
    assert m.times_ms[-1] <= MAX_MOTION_MS
    assert not np.any(np.isinf(m.values))  # NaN only for '*'


def check_scenario(path: Path) -> None:
    s = load_scenario(path)
    arrays = [s.start, s.targets, *s.obstacles,
              *(a for c in (s.arm, *s.fingers) for a in (c.length, c.min_deg, c.max_deg))]
    assert all(np.all(np.isfinite(a)) and np.all(np.abs(a) <= MAX_ABS) for a in arrays)
    assert s.width > 0 and s.height > 0 and s.start.shape == (2,)
    assert s.targets.shape == (len(s.fingers), 2) and len(s.fingers) >= 1
    assert all(o.ndim == 2 and o.shape[0] >= 2 and o.shape[1] == 2 for o in s.obstacles)
    for c in (s.arm, *s.fingers):
        assert c.n_bones >= 1 and np.all(c.length > 0)
        assert np.all((c.min_deg >= 0) & (c.min_deg <= c.max_deg) & (c.max_deg <= 360))


def check_map(path: Path) -> None:
    m = read_map(path)
    assert m.blocked.dtype == bool and m.blocked.ndim == 2
    assert m.height >= 1 and m.width >= 1 and m.height * m.width <= MAX_MAP_CELLS
    for x, y in (m.start, m.goal):
        assert 0 <= x < m.width and 0 <= y < m.height and not m.blocked[y, x]


def check_plan_file(path: Path) -> None:
    doc = read_plan(path)
    try:  # what `evomotion quadruped-plan check` does next: a verdict, never a crash
        check_plan(doc)
    except PlanViolationError as e:
        assert "\n" not in str(e)


def check_world(path: Path) -> None:
    w = read_world(path)
    x0, y0, x1, y1 = w.bounds
    assert x0 < x1 and y0 < y1 and w.goal_tolerance > 0 and w.view > 0
    assert x0 < w.start[0] < x1 and y0 < w.start[1] < y1 and np.isfinite(w.start).all()
    assert x0 < w.goal[0] < x1 and y0 < w.goal[1] < y1
    for p in w.polygons:
        assert p.kind in ("nostep", "obstacle", "hidden") and p.points.ndim == 2
        assert p.points.shape[0] >= 3 and p.points.shape[1] == 2
        assert np.isfinite(p.points).all()


READERS = {"motion": check_motion, "scenario": check_scenario, "movingai": check_map,
           "binary": check_map, "plan": check_plan_file, "world": check_world}


def seeds(reader: str) -> list[Path]:
    """The valid files the mutations start from."""
    if reader == "motion":
        return [SHOOT, *sorted(WEBOTS.glob("*.motion"))]
    if reader == "scenario":
        return sorted(SCENARIO_DIR.glob("*.scen"))
    if reader == "movingai":
        return sorted(MAPS.glob("*.map"))
    if reader == "binary":
        return sorted(DATA.glob("*.txt"))
    if reader == "world":
        return sorted(WORLD_DIR.glob("*.world"))
    return sorted(DATA.glob("*.json"))


def accepts_or_one_line_error(reader: str, path: Path) -> str:
    """Run the reader: "ok" when it accepts (and what it returns is valid), else the error
    message, which must be one line naming the file. Any other exception fails the test."""
    try:
        READERS[reader](path)
    except FileFormatError as e:
        msg = str(e)
        assert msg.startswith(str(path)) and "\n" not in msg and "\r" not in msg, msg
        return msg
    except InputError as e:  # maps: endpoints blocked / cut off (semantic, not format)
        assert reader in ("movingai", "binary") and "\n" not in str(e), str(e)
        return str(e)
    return "ok"
