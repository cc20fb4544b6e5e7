"""The ``internal/*`` cases of ``same_seed.py``: seeded runs through the studies' internal
Python functions (the comparison of issue 11, 58 outputs), run by ``same_seed.py`` in a child
process with the tree under test first on ``PYTHONPATH``:

    python benchmarks/same_seed_internal.py --child OUT.json --group grid-path

A group whose functions a tree no longer has (a module renamed or moved, a signature changed)
writes ``{"skipped": "ImportError: ..."}`` (or the AttributeError / TypeError); the CLI cases
of ``same_seed.py`` cover the same runs.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path


def grid_path() -> dict:
    """cGA policies / neighbourhoods and the panmictic GA on two seed maps (3 seeds, 30
    generations each) and continuous + repair on a random map: length, validity, convergence
    generation, genome."""
    from evomotion.studies.grid_path.experiments import algorithm_for, beyond_config
    from evomotion.studies.grid_path.problem import GridPathConfig, GridPathProblem

    try:
        from evomotion.studies.grid_path.experiments import evolve
    except ImportError:  # before issue 32 (evolve in experiments.py, run/in_memory.py)
        try:
            from evomotion.studies.grid_path.outcome import evolve
        except ImportError:  # before the one run loop
            from evomotion.studies.grid_path.driver import evolve
    out: dict = {}
    for mp, pop, m in (("seed10a", 100, 1.2), ("seed20", 400, 1.05)):
        p = GridPathProblem(GridPathConfig(map=mp, m=m))
        for row in ("cga-L5-line", "cga-C9-line", "cga-L5-sync", "cga-L5-new",
                    "cga-L5-uniform", "ga"):
            for s in range(3):
                r = evolve(p, algorithm_for(row, pop, 0.9, 0.2), s, 30)
                out[f"grid-path/{mp}/{row}/{s}"] = [r.length, r.valid, r.converged_generation,
                                                    r.genome.tolist(), r.evaluations]
    p = GridPathProblem(beyond_config("continuous+repair-r5", "random:20:0.25:3"))
    r = evolve(p, algorithm_for("cga-L5-sync", 100, 0.9, 0.2), 0, 50)
    out["grid-path/beyond"] = [r.length, r.valid, r.converged_generation, r.genome.tolist()]
    return out


def arm_ik() -> dict:
    """Four scenarios x 3 seeds: solved, generations, evaluations, restarts, best limb."""
    from evomotion.studies.arm_ik.problem import ArmIKConfig

    out: dict = {}
    for scen in ("seed_example", "corridor", "three_fingers", "four_fingers"):
        for s in range(3):
            try:
                try:
                    from evomotion.studies.arm_ik.experiment import evolve as arm_evolve
                except ImportError:  # before issue 32 (success.py became experiment.py)
                    from evomotion.studies.arm_ik.outcome import evolve as arm_evolve

                r = arm_evolve(ArmIKConfig(scenario=scen, pictures=False), s, wall_seconds=0)
            except ImportError:
                from evomotion.studies.arm_ik.schedule import evolve as arm_evolve

                r = arm_evolve(ArmIKConfig(scenario=scen, pictures=False, wall_seconds=1e9), s)
            out[f"arm-ik/{scen}/{s}"] = [r.solved, r.generations, r.evaluations, r.restarts,
                                         r.best.tolist()]
    return out


def quadruped_plan() -> dict:
    """Best-first with functions (1) and (3) on both rule sets from both starts (every state
    and rule) and a coarse-grid A*."""
    try:  # before issue 32 the study's modules were flat
        from evomotion.studies.quadruped_plan.plans.planner import QuadrupedPlanConfig, solve
    except ImportError:
        from evomotion.studies.quadruped_plan.planner import QuadrupedPlanConfig, solve

    try:
        from evomotion.studies.quadruped_plan.plans.search_config import SearchConfig

        def plan(search: dict, **task):
            return solve(QuadrupedPlanConfig(**task), SearchConfig(**search))
    except ImportError:  # before issue 32: the search settings were [problem] keys
        def plan(search: dict, **task):
            return solve(QuadrupedPlanConfig(**task, **search))
    out: dict = {}
    for fn in (1, 3):
        for rs in ("A", "B"):
            for start, phi in (("a", math.pi / 4), ("b", math.pi / 2)):
                r = plan({"function": fn, "max_seconds": 1e9}, rule_set=rs, start_phi=phi)
                out[f"quadruped-plan/{fn}/{rs}/{start}"] = [
                    r.stop_reason, r.expansions, len(r.states),
                    [list(s[:11]) for s in r.states], r.rules]
    r = plan({"method": "astar", "max_seconds": 1e9}, rule_set="B", start_phi=math.pi / 2,
             pos_grid=1, angle_grid=0.2, goal_x=-3, goal_y=3)
    out["quadruped-plan/astar-coarse"] = [r.stop_reason, r.expansions, len(r.states), r.rules]
    return out


GROUPS = {"grid-path": grid_path, "arm-ik": arm_ik, "quadruped-plan": quadruped_plan}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--child", required=True, help="write the group's outputs here (JSON)")
    ap.add_argument("--group", required=True, choices=sorted(GROUPS))
    a = ap.parse_args()
    t0 = time.perf_counter()
    try:
        res: dict = {"outputs": GROUPS[a.group]()}
    except (ImportError, AttributeError, TypeError) as e:  # the internal API changed: the
        res = {"skipped": f"{type(e).__name__}: {e}"}  # CLI cases still compare
    res["seconds"] = time.perf_counter() - t0
    Path(a.child).write_text(json.dumps(res))


if __name__ == "__main__":
    main()
