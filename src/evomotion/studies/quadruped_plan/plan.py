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
from evomotion.studies.quadruped_plan.model import (
    QuadrupedModel,
    lift_margin,
    support_margin,
    world_feet,
)
from evomotion.studies.quadruped_plan.rules import ExclusionZone, rule_leg

FORMAT = "evomotion.quadruped-plan/1"
LEG_NAMES = ("front-left", "rear-left", "rear-right", "front-right")


def state_margin(prev: tuple[float, ...] | None, state: tuple[float, ...], rule: int) -> float:
    if rule >= 4 and prev is not None:
        return lift_margin(prev, rule_leg(rule))
    return support_margin(state)


def plan_document(model: QuadrupedModel, states: list[tuple], rules: list[int | None],
                  goal: tuple[float, float], goal_tolerance: float, sense: int, rule_set: str,
                  zone: ExclusionZone | None, search: dict[str, Any]) -> dict[str, Any]:
    """The plan.json document for a found plan (``rules[0]`` is the start, None or 0)."""
    out_states = []
    prev = None
    for state, rule in zip(states, rules, strict=True):
        r = int(rule or 0)
        out_states.append({
            "body": [state[0], state[1], state[2]],
            "feet": [list(f) for f in world_feet(state)],
            "rule": r,
            "margin": state_margin(prev, state, r),
        })
        prev = state
    return {
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


def write_plan(path: str | Path, doc: dict[str, Any]) -> None:
    path = Path(path)
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(doc, indent=1) + "\n")
    tmp.replace(path)


def _number(path: Path, x: Any, what: str) -> float:
    if isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(x):
        raise FileFormatError(path, None, f"expected a finite number for {what}, got {x!r}")
    return float(x)


def read_plan(path: str | Path) -> dict[str, Any]:
    """Load and shape-check a plan.json (values are checked by ``checker``)."""
    path = Path(path)
    try:
        doc = json.loads(path.read_text())
    except FileNotFoundError:
        raise FileFormatError(path, None, "expected an existing plan.json file") from None
    except json.JSONDecodeError as e:
        raise FileFormatError(path, e.lineno, f"expected JSON ({e.msg})") from None
    if not isinstance(doc, dict):
        raise FileFormatError(path, None, "expected a JSON object")
    for key in ("model", "goal", "goal_tolerance", "rule_set", "states"):
        if key not in doc:
            raise FileFormatError(path, None, f"expected key {key!r}")
    m = doc["model"]
    for key in ("a", "b", "l_min", "l_max", "sector_half_width"):
        if not isinstance(m, dict) or key not in m:
            raise FileFormatError(path, None, f"expected model key {key!r}")
        _number(path, m[key], f"model.{key}")
    if not isinstance(doc["states"], list) or not doc["states"]:
        raise FileFormatError(path, None, "expected a non-empty list 'states'")
    for i, st in enumerate(doc["states"]):
        ok = (isinstance(st, dict) and isinstance(st.get("body"), list)
              and len(st["body"]) == 3 and isinstance(st.get("feet"), list)
              and len(st["feet"]) == 4 and all(isinstance(f, list) and len(f) == 2
                                               for f in st["feet"])
              and isinstance(st.get("rule"), int) and "margin" in st)
        if not ok:
            raise FileFormatError(path, None, f"expected state {i} as {{body: [x, y, phi], "
                                  "feet: [[x, y] x 4], rule: int, margin: number}")
        for v in (*st["body"], *(c for f in st["feet"] for c in f), st["margin"]):
            _number(path, v, f"states[{i}]")
    return doc


def model_from_plan(doc: dict[str, Any]) -> QuadrupedModel:
    m = doc["model"]
    return QuadrupedModel(a=m["a"], b=m["b"], l_min=m["l_min"], l_max=m["l_max"],
                          sector_half_width=m["sector_half_width"],
                          min_margin=m.get("min_margin", 0.0))
