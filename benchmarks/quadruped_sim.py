"""Simulated execution of quadruped plans on the MuJoCo quadruped (issue 16).

Plans: the paper's four start / rule-set plans (best-first, function (1), as in the paper's
first experiment) and one plan per bundled world (the receding-horizon walker without
disturbances, rule set B, 5,000 expansions per replan: an offline plan), each also made
*robust*: planned with a lift margin of 0.1 units
and the body shifts (rules 28-31; function (3) for the paper's task). Each plan is executed
quasi-statically (:func:`evomotion.sim.quadruped.execute_plan`); printed: whether the body
stayed up, the least support margin from the contact forces, the largest tilt, the final
position / heading error, simulated and wall time. ``--video DIR`` also renders each world's
robust plan to DIR/<world>.mp4.

    python benchmarks/quadruped_sim.py [--video DIR] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np


def paper_plans(robust: bool) -> list[tuple[str, dict]]:
    from evomotion.studies.quadruped_plan.plans.plan import plan_document
    from evomotion.studies.quadruped_plan.plans.planner import (
        QuadrupedPlanConfig,
        make_problem,
        solve,
    )
    from evomotion.studies.quadruped_plan.plans.search_config import SearchConfig

    out = []
    search = SearchConfig(function=3 if robust else 1, max_expansions=300_000)
    for rs in "AB":
        for label, phi in (("a", math.pi / 4), ("b", 1.5 * math.pi)):
            cfg = QuadrupedPlanConfig(rule_set=rs, start_phi=phi,
                                      min_margin=0.1 if robust else 0.0, shifts=robust)
            p = make_problem(cfg)
            res = solve(cfg, search, p)
            if not res.found:
                out.append((f"paper {rs}/{label}", {}))
                continue
            doc = plan_document(p.model, res.states, res.rules, p.goal, p.goal_tolerance,
                                cfg.sense, rs, None, {})
            doc["shifts"] = robust
            out.append((f"paper {rs}/{label}", doc))
    return out


def _search_plan(world: str, robust: bool) -> dict:
    from evomotion.studies.quadruped_plan.plans.plan import plan_document, world_section
    from evomotion.studies.quadruped_plan.plans.planner import (
        QuadrupedPlanConfig,
        make_problem,
        solve,
    )

    cfg = QuadrupedPlanConfig(world=world, min_margin=0.1 if robust else 0.0, shifts=robust)
    p = make_problem(cfg)
    res = solve(cfg, None, p)
    if not res.found:
        return {}
    doc = plan_document(p.model, res.states, res.rules, p.goal, p.goal_tolerance, cfg.sense,
                        cfg.rule_set, None, {}, world_section(p.terrain.world, 0.05, 0.05))
    doc["shifts"] = robust
    return doc


def world_plans(robust: bool) -> list[tuple[str, dict]]:
    from evomotion.studies.quadruped_plan.missions.doc import mission_document
    from evomotion.studies.quadruped_plan.missions.mission import (
        Disturbances,
        Mission,
        ReplanSettings,
        run_mission,
    )
    from evomotion.studies.quadruped_plan.rules.model import QuadrupedModel
    from evomotion.studies.quadruped_plan.worlds.world import bundled_worlds, load_world

    out = []
    for name in bundled_worlds():
        m = Mission(load_world(name), QuadrupedModel(min_margin=0.1 if robust else 0.0), "B",
                    disturb=Disturbances(0.0, 0.0, 0.0, 0.0, 0.0), shifts=robust,
                    settings=ReplanSettings(replan_expansions=5_000))
        st = run_mission(m, np.random.default_rng(0))
        if st.done == "reached":
            out.append((f"world {name}", mission_document(m, st)))
        else:  # one search to the goal (no detour needed in gaps)
            out.append((f"world {name} (search)", _search_plan(name, robust)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--video", type=Path)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()

    from evomotion.studies.quadruped_plan.plans.checker import check_plan
    from evomotion.studies.quadruped_plan.plans.simulate import simulate_document

    rows = []
    print(f"{time.strftime('%Y-%m-%d %H:%M')}")
    print(f"{'plan':>15} {'variant':>7} {'states':>6} {'body up':>7} {'margin mm':>9} "
          f"{'tilt deg':>8} {'err mm':>7} {'err deg':>7} {'sim s':>6} {'wall s':>6}")
    for robust in (False, True):
        for label, doc in [*paper_plans(robust), *world_plans(robust)]:
            variant = "robust" if robust else "paper"
            if not doc:
                print(f"{label:>15} {variant:>7}  no plan")
                continue
            check_plan(doc)
            video = None
            if args.video and robust and label.startswith("world"):
                args.video.mkdir(parents=True, exist_ok=True)
                video = args.video / f"{label.split()[1]}.mp4"
            r = simulate_document(doc, video)
            rows.append({"plan": label, "variant": variant, "states": len(doc["states"]), **r})
            margin = r["min_support_margin_m"]
            print(f"{label:>15} {variant:>7} {len(doc['states']):>6} "
                  f"{'yes' if r['body_up'] else 'FELL':>7} "
                  f"{'-' if margin is None else f'{1000 * margin:.1f}':>9} "
                  f"{math.degrees(r['max_tilt_rad'] or 0):>8.1f} "
                  f"{1000 * (r['final_position_error_m'] or math.nan):>7.1f} "
                  f"{math.degrees(r['final_heading_error_rad'] or math.nan):>7.1f} "
                  f"{r['duration_s']:>6.0f} {r['wall_seconds']:>6.1f}")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
