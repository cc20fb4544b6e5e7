"""Same-seed comparison of the seed reproductions against another revision, with timings.

Runs a fixed set of seeded runs of grid-path (cGA policies and the panmictic GA on seed maps,
continuous + repair on a random map), arm-ik (three scenarios) and quadruped-plan (best-first
with functions 1 and 3 on both rule sets, coarse-grid A*) in this tree and in the package as
committed at ``--baseline REV`` (exported with ``git archive``), each in its own process, and
prints which outputs differ and the time ratio of each group measured in the same run.

    python benchmarks/same_seed.py --baseline d61c970 [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from baseline import export, run_child  # noqa: E402


def outputs() -> dict:
    """The outputs and timings of this interpreter's ``evomotion`` (old or new API)."""
    import math

    from evomotion.studies.grid_path.experiments import algorithm_for, beyond_config
    from evomotion.studies.grid_path.problem import GridPathConfig, GridPathProblem

    try:
        from evomotion.studies.grid_path.outcome import evolve
    except ImportError:  # before the one run loop
        from evomotion.studies.grid_path.driver import evolve
    out: dict = {}
    times: dict = {}
    t0 = time.perf_counter()
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
    times["grid-path"] = time.perf_counter() - t0

    from evomotion.studies.arm_ik.problem import ArmIKConfig

    t0 = time.perf_counter()
    for scen in ("seed_example", "corridor", "three_fingers", "four_fingers"):
        for s in range(3):
            try:
                from evomotion.studies.arm_ik.outcome import evolve as arm_evolve

                r = arm_evolve(ArmIKConfig(scenario=scen, pictures=False), s, wall_seconds=0)
            except ImportError:
                from evomotion.studies.arm_ik.schedule import evolve as arm_evolve

                r = arm_evolve(ArmIKConfig(scenario=scen, pictures=False, wall_seconds=1e9), s)
            out[f"arm-ik/{scen}/{s}"] = [r.solved, r.generations, r.evaluations, r.restarts,
                                         r.best.tolist()]
    times["arm-ik"] = time.perf_counter() - t0

    from evomotion.studies.quadruped_plan.planner import QuadrupedPlanConfig, solve

    t0 = time.perf_counter()
    for fn in (1, 3):
        for rs in ("A", "B"):
            for start, phi in (("a", math.pi / 4), ("b", math.pi / 2)):
                r = solve(QuadrupedPlanConfig(function=fn, rule_set=rs, start_phi=phi,
                                              max_seconds=1e9))
                out[f"quadruped-plan/{fn}/{rs}/{start}"] = [
                    r.stop_reason, r.expansions, len(r.states),
                    [list(s[:11]) for s in r.states], r.rules]
    r = solve(QuadrupedPlanConfig(method="astar", rule_set="B", start_phi=math.pi / 2,
                                  pos_grid=1, angle_grid=0.2, max_seconds=1e9, goal_x=-3,
                                  goal_y=3))
    out["quadruped-plan/astar-coarse"] = [r.stop_reason, r.expansions, len(r.states), r.rules]
    times["quadruped-plan"] = time.perf_counter() - t0
    return {"outputs": out, "times": times}


def run_in(src: Path | None) -> dict:
    return run_child(__file__, src)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--baseline", required=False, default="HEAD")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--child", default=None)
    a = ap.parse_args()
    if a.child:
        Path(a.child).write_text(json.dumps(outputs()))
        return
    with tempfile.TemporaryDirectory() as tmp:
        src = export(a.baseline, Path(tmp))
        new_t, old_t = [], []
        for _ in range(a.repeat):  # interleaved, so both see the same load
            old = run_in(src)
            new = run_in(None)
            old_t.append(old["times"])
            new_t.append(new["times"])
    differ = [k for k in old["outputs"] if old["outputs"][k] != new["outputs"].get(k)]
    print(f"compared {len(old['outputs'])} same-seed outputs with {a.baseline}: "
          f"{len(differ)} differ")
    for k in differ:
        print(f"  differs: {k}")
    print("| group | baseline s | this tree s | ratio (this / baseline) |\n|---|---|---|---|")
    for g in old["times"]:
        o, n = min(t[g] for t in old_t), min(t[g] for t in new_t)
        print(f"| {g} | {o:.2f} | {n:.2f} | {n / o:.2f} |")


if __name__ == "__main__":
    main()
