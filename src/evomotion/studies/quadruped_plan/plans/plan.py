"""``plan.json``: a walking plan with the model parameters it was made for.

Keys (stable; other tools read them)::

    {"format": "evomotion.quadruped-plan/1",
     "model": {"a", "b", "l_min", "l_max", "sector_half_width", "min_margin",
               "hips": [[x, y] x 4], "legs": ["front-left", ...]},
     "goal": [x, y], "goal_tolerance": r, "sense": -1|0|1, "rule_set": "A"|"B",
     "zone": null | {"x", "y", "radius"},
     "search": {...},
     "states": [{"body": [x, y, phi], "feet": [[x, y] x 4], "rule": n, "margin": m}, ...]}

``feet`` are world coordinates in leg index order; ``rule`` is the rule that produced the
state (0 for the start state); ``margin`` is the stability margin [units]: for a leg move
the body centre against the triangle of the three feet that stayed down, otherwise
against the support polygon of all four feet.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from evomotion.errors import FileFormatError
from evomotion.outfile import atomic_write_text
from evomotion.studies.quadruped_plan.rules.model import (
    QuadrupedModel,
    lift_margin,
    support_margin,
    world_feet,
)
from evomotion.studies.quadruped_plan.rules.rules import ExclusionZone, is_leg_rule, rule_leg
from evomotion.textio import decode_utf8, json_depth, loads_json, read_file_bytes

FORMAT = "evomotion.quadruped-plan/1"
LEG_NAMES = ("front-left", "rear-left", "rear-right", "front-right")


def state_margin(prev: tuple[float, ...] | None, state: tuple[float, ...], rule: int) -> float:
    if is_leg_rule(rule) and prev is not None:
        return lift_margin(prev, rule_leg(rule))
    return support_margin(state)


def plan_document(model: QuadrupedModel, states: list[tuple], rules: list[int | None],
                  goal: tuple[float, float], goal_tolerance: float, sense: int, rule_set: str,
                  zone: ExclusionZone | None, search: dict[str, Any],
                  world: dict[str, Any] | None = None,
                  extras: list[dict[str, Any]] | None = None) -> dict[str, Any]:
    """The plan.json document for a found plan (``rules[0]`` is the start, None or 0).

    ``world``: the world's polygons and clearances (:func:`world_section`); ``extras``: keys
    added to each state (an executed walk's ``event`` and ``target``)."""
    out_states = []
    prev = None
    for k, (state, rule) in enumerate(zip(states, rules, strict=True)):
        r = int(rule or 0)
        out_states.append({
            "body": [state[0], state[1], state[2]],
            "feet": [list(f) for f in world_feet(state)],
            "rule": r,
            "margin": state_margin(prev, state, r),
            **(extras[k] if extras else {}),
        })
        prev = state
    doc = {
        "format": FORMAT,
        "model": {"a": model.a, "b": model.b, "l_min": model.l_min, "l_max": model.l_max,
                  "sector_half_width": model.sector_half_width,
                  "min_margin": model.min_margin,
                  "hips": [list(h) for h in model.hips], "legs": list(LEG_NAMES)},
        "goal": list(goal), "goal_tolerance": goal_tolerance, "sense": sense,
        "rule_set": rule_set,
        "zone": None if zone is None else {"x": zone.x, "y": zone.y, "radius": zone.radius},
        "search": search,
        "states": out_states,
    }
    if world is not None:
        doc["world"] = world
    return doc


def world_section(world: Any, body_clearance: float, foot_clearance: float,
                  polygons: list[tuple[str, list, int]] | None = None) -> dict[str, Any]:
    """The ``world`` key of plan.json: bounds, clearances and polygons ``{"kind", "points",
    "from"}`` (``from``: the state index from which an obstacle exists or is known; hidden
    obstacles are real from the start, 0)."""
    polys = [{"kind": "obstacle" if p.kind == "hidden" else p.kind,
              "hidden": p.kind == "hidden", "points": p.points.tolist(), "from": 0}
             for p in world.polygons]
    for kind, points, index in polygons or []:
        polys.append({"kind": kind, "hidden": False, "points": points, "from": index})
    return {"name": world.name, "bounds": list(world.bounds),
            "body_clearance": body_clearance, "foot_clearance": foot_clearance,
            "polygons": polys}


def write_plan(path: str | Path, doc: dict[str, Any], what: str = "plan") -> None:
    """``doc`` as indented JSON, written atomically (:mod:`evomotion.outfile`)."""
    atomic_write_text(path, json.dumps(doc, indent=1, allow_nan=False) + "\n", what)


MAX_PLAN_BYTES = 16 * 1024 * 1024  # a 10,000-state walk is ~5 MB
MAX_ABS = 1e6  # [units]: the largest coordinate or model length read
MAX_STATES = 10_000  # 3,333 transitions with a landing error and a slip each; ~15 s to check
MAX_POLYGONS = 1_000  # a world's 500 and the posts that appeared
MAX_POLYGON_VERTICES = 1_000
MAX_TOTAL_VERTICES = 25_000
MAX_DEPTH = 32  # JSON nesting (a plan has 5 levels)
MAX_INT = 2 ** 53  # integers anywhere in a plan (larger ones are not exact as floats)


def _got(x: Any) -> str:
    try:
        text = json.dumps(x, allow_nan=True)
    except (TypeError, ValueError):
        text = repr(x)
    return text if len(text) <= 40 else text[:40] + "..."


class _Checker:
    """Field checks whose errors read ``FILE: KEY.PATH: expected ..., got VALUE``."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def fail(self, where: str, expected: str, x: Any = ...) -> FileFormatError:
        got = "" if x is ... else f", got {_got(x)}"
        return FileFormatError(self.path, None, f"{where}: expected {expected}{got}")

    def get(self, obj: dict, key: str, where: str) -> Any:
        if key not in obj:
            raise FileFormatError(self.path, None, f"expected {where} key {key!r}")
        return obj[key]

    def number(self, x: Any, where: str, lo: float = -MAX_ABS, hi: float = MAX_ABS,
               what: str = "a finite number") -> float:
        if isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(x) \
                or not lo <= x <= hi:
            raise self.fail(where, f"{what} in [{lo:g}, {hi:g}]", x)
        return float(x)

    def point(self, x: Any, where: str, n: int, text: str) -> None:
        if not (isinstance(x, list) and len(x) == n):
            raise self.fail(where, f"{text} numbers", x)
        for k, v in enumerate(x):
            if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) \
                    or abs(v) > MAX_ABS:
                raise self.fail(f"{where}[{k}]", f"a finite number of magnitude <= {MAX_ABS:g}"
                                f" (in {text})", v)

    def obj(self, x: Any, where: str) -> dict:
        if not isinstance(x, dict):
            raise self.fail(where, "a JSON object", x)
        return x


def _check_document(path: Path, doc: Any) -> None:
    c = _Checker(path)
    if not isinstance(doc, dict):
        raise FileFormatError(path, None, f"expected a JSON object, got {_got(doc)}")
    if "format" in doc and doc["format"] != FORMAT:
        raise c.fail("format", repr(FORMAT), doc["format"])
    m = c.obj(c.get(doc, "model", "model"), "model")
    a = c.number(c.get(m, "a", "model"), "model.a", 1e-9)
    b = c.number(c.get(m, "b", "model"), "model.b", 1e-9)
    lo = c.number(c.get(m, "l_min", "model"), "model.l_min", 0.0)
    c.number(c.get(m, "l_max", "model"), "model.l_max", lo, what="a finite number >= l_min")
    c.number(c.get(m, "sector_half_width", "model"), "model.sector_half_width", 0.0,
             math.pi, "an angle [rad]")
    if "min_margin" in m:
        c.number(m["min_margin"], "model.min_margin", 0.0)
    if "hips" in m:
        hips = m["hips"]
        if not (isinstance(hips, list) and len(hips) == 4):
            raise c.fail("model.hips", "4 hips [x, y]", hips)
        for k, h in enumerate(hips):
            c.point(h, f"model.hips[{k}]", 2, "[x, y]")
    if "legs" in m and not (isinstance(m["legs"], list) and len(m["legs"]) == 4
                            and all(isinstance(n, str) for n in m["legs"])):
        raise c.fail("model.legs", "4 leg names", m["legs"])
    del a, b
    c.point(c.get(doc, "goal", "plan"), "goal", 2, "[x, y]")
    c.number(c.get(doc, "goal_tolerance", "plan"), "goal_tolerance", 0.0)
    if "sense" in doc and (isinstance(doc["sense"], bool) or doc["sense"] not in (-1, 0, 1)):
        raise c.fail("sense", "-1, 0 or 1", doc["sense"])
    rule_set = c.get(doc, "rule_set", "plan")
    if rule_set not in ("A", "B"):
        raise c.fail("rule_set", "'A' or 'B'", rule_set)
    zone = doc.get("zone")
    if zone is not None:
        c.obj(zone, "zone")
        c.number(c.get(zone, "x", "zone"), "zone.x")
        c.number(c.get(zone, "y", "zone"), "zone.y")
        c.number(c.get(zone, "radius", "zone"), "zone.radius", 0.0)
    if "search" in doc:
        c.obj(doc["search"], "search")
    if doc.get("world") is not None:
        _check_world(c, c.obj(doc["world"], "world"))
    if "goal_history" in doc:
        _check_history(c, doc)
    for key in ("executed", "shifts"):
        if key in doc and not isinstance(doc[key], bool):
            raise c.fail(key, "true or false", doc[key])
    if "disturbance_max" in doc:
        c.number(doc["disturbance_max"], "disturbance_max", 0.0)
    states = c.get(doc, "states", "plan")
    if not (isinstance(states, list) and 1 <= len(states) <= MAX_STATES):
        raise c.fail("states", f"a list of 1 to {MAX_STATES:,} states", states)
    for i, st in enumerate(states):
        where = f"states[{i}]"
        c.obj(st, where)
        c.point(c.get(st, "body", where), f"{where}.body", 3, "[x, y, phi]")
        feet = c.get(st, "feet", where)
        if not (isinstance(feet, list) and len(feet) == 4):
            raise c.fail(f"{where}.feet", "4 feet [x, y]", feet)
        for k, f in enumerate(feet):
            c.point(f, f"{where}.feet[{k}]", 2, "[x, y]")
        rule = c.get(st, "rule", where)
        if isinstance(rule, bool) or not isinstance(rule, int) or not 0 <= rule <= 1000:
            raise c.fail(f"{where}.rule", "a rule number (an integer in [0, 1000])", rule)
        c.number(c.get(st, "margin", where), f"{where}.margin")
        if "event" in st and not (isinstance(st["event"], str) and len(st["event"]) <= 40):
            raise c.fail(f"{where}.event", "a short string", st["event"])
        if "target" in st:
            c.point(st["target"], f"{where}.target", 2, "[x, y]")
    _check_numbers(c, doc, "")


def _check_world(c: _Checker, w: dict) -> None:
    c.point(c.get(w, "bounds", "world"), "world.bounds", 4, "[xmin, ymin, xmax, ymax]")
    for key in ("body_clearance", "foot_clearance"):
        if key in w:
            c.number(w[key], f"world.{key}", 0.0)
    polys = c.get(w, "polygons", "world")
    if not (isinstance(polys, list) and len(polys) <= MAX_POLYGONS):
        raise c.fail("world.polygons", f"a list of at most {MAX_POLYGONS:,} polygons", polys)
    total = 0
    for k, p in enumerate(polys):
        where = f"world.polygons[{k}]"
        c.obj(p, where)
        if c.get(p, "kind", where) not in ("nostep", "obstacle"):
            raise c.fail(f"{where}.kind", "'nostep' or 'obstacle'", p["kind"])
        pts = c.get(p, "points", where)
        if not (isinstance(pts, list) and 3 <= len(pts) <= MAX_POLYGON_VERTICES):
            raise c.fail(f"{where}.points", f"a list of 3 to {MAX_POLYGON_VERTICES:,} [x, y]",
                         pts)
        total += len(pts)
        if total > MAX_TOTAL_VERTICES:
            raise c.fail(f"{where}.points", f"at most {MAX_TOTAL_VERTICES:,} vertices in all "
                         "the world's polygons")
        for j, q in enumerate(pts):
            c.point(q, f"{where}.points[{j}]", 2, "[x, y]")
        frm = p.get("from", 0)
        if isinstance(frm, bool) or not isinstance(frm, int) or not 0 <= frm <= MAX_STATES:
            raise c.fail(f"{where}.from", "a state index >= 0", frm)
        if "hidden" in p and not isinstance(p["hidden"], bool):
            raise c.fail(f"{where}.hidden", "true or false", p["hidden"])
    if "name" in w and not (isinstance(w["name"], str) and len(w["name"]) <= 200):
        raise c.fail("world.name", "a short string", w["name"])


def _check_history(c: _Checker, doc: dict) -> None:
    """``goal_history`` of an executed walk: ``[{"goal": [x, y], "from": index}, ...]``."""
    hist = doc["goal_history"]
    if not (isinstance(hist, list) and 1 <= len(hist) <= 100):
        raise c.fail("goal_history", "a list of 1 to 100 goals", hist)
    for k, h in enumerate(hist):
        c.obj(h, f"goal_history[{k}]")
        c.point(c.get(h, "goal", f"goal_history[{k}]"), f"goal_history[{k}].goal", 2, "[x, y]")
        frm = c.get(h, "from", f"goal_history[{k}]")
        if isinstance(frm, bool) or not isinstance(frm, int) or not 0 <= frm <= MAX_STATES:
            raise c.fail(f"goal_history[{k}].from", "a state index >= 0", frm)


def _check_numbers(c: _Checker, x: Any, where: str) -> None:
    """Every number anywhere in the document finite and every integer below 2**53 (the
    fields above are checked with their ranges; this covers ``search`` and the rest)."""
    if isinstance(x, dict):
        for k, v in x.items():
            _check_numbers(c, v, f"{where}.{k}" if where else str(k)[:40])
    elif isinstance(x, list):
        for k, v in enumerate(x):
            _check_numbers(c, v, f"{where}[{k}]")
    elif isinstance(x, float) and not math.isfinite(x):
        raise c.fail(where, "a finite number", x)
    elif isinstance(x, int) and not isinstance(x, bool) and abs(x) > MAX_INT:
        raise c.fail(where, "an integer of magnitude <= 2**53", x)


def _loads(text: str, path: Path) -> Any:
    """The JSON document (nesting at most ``MAX_DEPTH``: no RecursionError; ``NaN`` and
    ``Infinity`` are parsed and then refused with the key that holds them)."""
    if json_depth(text, MAX_DEPTH) > MAX_DEPTH:
        raise FileFormatError(path, None, f"expected JSON nested less deeply (at most "
                              f"{MAX_DEPTH} levels)")
    try:
        return loads_json(text, path, MAX_DEPTH, finite=False)
    except FileFormatError as e:
        if e.expected.startswith("invalid JSON (ValueError"):  # > 4,300 digits
            raise FileFormatError(path, None, "expected JSON numbers (an integer of more "
                                  "than 4,300 digits)") from None
        if "invalid JSON" in e.expected:
            raise FileFormatError(path, e.line, e.expected.replace("invalid JSON",
                                                                   "expected JSON")) from None
        raise


def read_plan(path: str | Path) -> dict[str, Any]:
    """Load and check a plan.json: every field the checker and the views use, with the
    field's path in the message (``plan.json: goal: expected [x, y] numbers, got "abc"``);
    whether the plan obeys the model is ``checker``'s business."""
    path = Path(path)
    text = decode_utf8(read_file_bytes(path, "plan.json file", MAX_PLAN_BYTES), path,
                       bom=False)
    doc = _loads(text, path)
    _check_document(path, doc)
    return doc


def model_from_plan(doc: dict[str, Any]) -> QuadrupedModel:
    m = doc["model"]
    return QuadrupedModel(a=m["a"], b=m["b"], l_min=m["l_min"], l_max=m["l_max"],
                          sector_half_width=m["sector_half_width"],
                          min_margin=m.get("min_margin", 0.0))
