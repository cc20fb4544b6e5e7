"""Receding-horizon walks against one-shot plans: bundled worlds x seeds x rule sets x
heuristics (``evomotion quadruped-plan missions``).

For every world and configuration, ``seeds`` walks with disturbances drawn from
``numpy.random.default_rng(seed)``; each executed walk is re-verified by the independent
checker (a walk that ends away from the goal is checked for everything but the end). The
one-shot plan is made once per world and configuration (it has no randomness) and executed
open loop with the same seeds' disturbances.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from evomotion.studies.quadruped_plan.missions.doc import mission_document
from evomotion.studies.quadruped_plan.missions.mission import (
    Disturbances,
    Mission,
    ReplanSettings,
    run_mission,
    summary,
)
from evomotion.studies.quadruped_plan.missions.oneshot import one_shot, plan_once
from evomotion.studies.quadruped_plan.plans.checker import PlanViolationError, check_plan
from evomotion.studies.quadruped_plan.rules.model import QuadrupedModel
from evomotion.studies.quadruped_plan.worlds.world import load_world


@dataclass
class Row:
    world: str
    rule_set: str
    heuristic: str
    shifts: bool
    walks: list[dict[str, Any]] = field(default_factory=list)
    shots: list[dict[str, Any]] = field(default_factory=list)
    one_shot_ms: float = math.nan
    check_failures: list[str] = field(default_factory=list)

    def figures(self) -> dict[str, Any]:
        ok = [w for w in self.walks if w["reached"]]
        ms = [m for w in self.walks for m in w["plan_ms"]]
        return {
            "world": self.world, "rule_set": self.rule_set, "heuristic": self.heuristic,
            "shifts": self.shifts, "seeds": len(self.walks),
            "success": len(ok) / max(1, len(self.walks)),
            "transitions": float(np.mean([w["transitions"] for w in ok])) if ok else math.nan,
            "replans": float(np.mean([w["replans"] for w in ok])) if ok else math.nan,
            "plan_ms_median": float(np.median(ms)) if ms else math.nan,
            "plan_ms_max": float(np.max(ms)) if ms else math.nan,
            "expansions_per_s": float(sum(w["expansions"] for w in self.walks) /
                                      max(1e-9, sum(ms) / 1000.0)),
            "recoveries": int(sum(w["recoveries"] for w in self.walks)),
            "bounded_share": (sum(w["bounded_replans"] for w in self.walks) /
                              max(1, sum(w["replans"] for w in self.walks))),
            "bound_median": float(np.median([b for w in self.walks for b in w["bounds"]]))
            if any(w["bounds"] for w in self.walks) else math.nan,
            "one_shot_success": (sum(s["reached"] for s in self.shots) / len(self.shots)
                                 if self.shots else math.nan),
            "one_shot_transitions": (self.shots[0]["planned_transitions"] if self.shots
                                     else 0),
            "one_shot_plan_ms": self.one_shot_ms,
            "checked": len(self.walks) - len(self.check_failures),
        }


def run_row(world_name: str, rule_set: str, heuristic: str, seeds: int, shifts: bool = False,
            settings: ReplanSettings | None = None,
            disturb: Disturbances | None = None) -> Row:
    world = load_world(world_name)
    mission = Mission(world, QuadrupedModel(), rule_set, -1, heuristic,
                      settings or ReplanSettings(), disturb or Disturbances(), shifts=shifts)
    row = Row(world.name, rule_set, heuristic, shifts)
    planned = plan_once(mission)
    row.one_shot_ms = planned[1]
    for seed in range(seeds):
        st = run_mission(mission, np.random.default_rng(seed))
        s = summary(st)
        s["plan_ms"] = list(st.plan_ms)
        s["bounds"] = [b for b in st.bounds if math.isfinite(b)]
        row.walks.append(s)
        try:
            check_plan(mission_document(mission, st))
        except PlanViolationError as e:
            if st.done == "reached" or "from the goal" not in str(e):
                row.check_failures.append(f"seed {seed}: {e}")
        shot = one_shot(mission, np.random.default_rng(seed), planned)
        shot.pop("state")
        row.shots.append(shot)
    return row


HEADER = ("world", "set", "h", "shifts", "success", "trans", "replans", "ms med", "ms max",
          "exp/s", "recov", "bounded", "1-shot ok", "1-shot trans", "1-shot ms", "checked")


def format_rows(rows: list[Row]) -> str:
    lines = ["  ".join(f"{h:>9}" for h in HEADER)]
    for r in rows:
        f = r.figures()
        lines.append("  ".join(f"{v:>9}" for v in (
            f["world"], f["rule_set"], f["heuristic"][:4], "yes" if f["shifts"] else "no",
            f"{100 * f['success']:.0f}%", f"{f['transitions']:.0f}", f"{f['replans']:.1f}",
            f"{f['plan_ms_median']:.1f}", f"{f['plan_ms_max']:.0f}",
            f"{f['expansions_per_s']:.0f}", f"{f['recoveries']}",
            f"{100 * f['bounded_share']:.0f}%",
            f"{100 * f['one_shot_success']:.0f}%", f"{f['one_shot_transitions']}",
            f"{f['one_shot_plan_ms']:.0f}", f"{f['checked']}/{f['seeds']}")))
    return "\n".join(lines)
