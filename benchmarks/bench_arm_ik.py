"""arm-ik (paper 001) benchmarks.

1. Population evaluations per second at population 200 on the largest bundled scenario
   (``four_fingers``): the vectorized ``ArmIKProblem.assess`` against a per-individual Python
   loop doing the same work (FK with ``math``, segment tests, permutation matching). The two
   are checked to agree before timing. Target: >= 30x.
2. Success rate and median time to the first solution over ``--seeds`` seeds per bundled
   scenario (unreachable excluded), per matching. Target: >= 95% and < 2 s median.

    python benchmarks/bench_arm_ik.py --part speed
    python benchmarks/bench_arm_ik.py --part success --seeds 20 --matching optimal greedy
    python benchmarks/bench_arm_ik.py --part ablation --seeds 10 --wall 10 \
        --scenario three_fingers four_fingers
"""

from __future__ import annotations

import argparse
import itertools
import math
import time

import numpy as np

from evomotion.studies.arm_ik.experiment import evolve, split_overrides, success_table
from evomotion.studies.arm_ik.problem import ArmIKConfig, ArmIKProblem
from evomotion.studies.arm_ik.scenario import bundled_names
from evomotion.studies.arm_ik.schedule import ScheduleConfig


def _orient(a, b, c):
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])


def _on(a, b, p):
    return min(a[0], b[0]) <= p[0] <= max(a[0], b[0]) and min(a[1], b[1]) <= p[1] <= max(a[1], b[1])


def _hit(p1, p2, q1, q2):
    d1, d2 = _orient(q1, q2, p1), _orient(q1, q2, p2)
    d3, d4 = _orient(p1, p2, q1), _orient(p1, p2, q2)
    if ((d1 > 0 > d2) or (d1 < 0 < d2)) and ((d3 > 0 > d4) or (d3 < 0 < d4)):
        return True
    return ((d1 == 0 and _on(q1, q2, p1)) or (d2 == 0 and _on(q1, q2, p2))
            or (d3 == 0 and _on(p1, p2, q1)) or (d4 == 0 and _on(p1, p2, q2)))


def loop_assess(prob: ArmIKProblem, genomes: np.ndarray) -> tuple[list[int], list[float]]:
    """Per-individual Python reference: (intersections, matched distance sum) per genome."""
    scn, lay = prob.scn, prob.layout
    obst = [(tuple(s[0]), tuple(s[1])) for s in scn.obstacle_segments()]
    targets = [tuple(t) for t in scn.targets]
    perms = list(itertools.permutations(range(len(targets))))
    hits_out, dist_out = [], []
    for g in genomes.tolist():
        x, y, phi = float(scn.start[0]), float(scn.start[1]), 0.0
        segs, joints = [], []
        for k in range(lay.n_arm):
            phi += math.radians(g[k])
            nx, ny = x + scn.arm.length[k] * math.cos(phi), y + scn.arm.length[k] * math.sin(phi)
            segs.append(((x, y), (nx, ny)))
            joints.append((nx, ny))
            x, y = nx, ny
        tips, col = [], lay.n_arm
        for f in scn.fingers:
            fx, fy, psi = x, y, phi
            for k in range(f.n_bones):
                psi += math.radians(g[col])
                col += 1
                nx, ny = fx + f.length[k] * math.cos(psi), fy + f.length[k] * math.sin(psi)
                segs.append(((fx, fy), (nx, ny)))
                joints.append((nx, ny))
                fx, fy = nx, ny
            tips.append((fx, fy))
        hits = sum(_hit(a, b, c, d) for a, b in segs for c, d in obst)
        hits += sum(not (0 <= px <= scn.width and 0 <= py <= scn.height) for px, py in joints)
        best = min(sum(math.dist(tips[f], targets[p[f]]) for f in range(len(tips)))
                   for p in perms)
        hits_out.append(hits)
        dist_out.append(best)
    return hits_out, dist_out


def speed(pop: int = 200, scenario: str = "four_fingers", repeats: int = 20) -> float:
    prob = ArmIKProblem(ArmIKConfig(scenario=scenario))
    g = prob.genome.sample(np.random.default_rng(0), pop)
    a = prob.assess(g)
    hits, dist = loop_assess(prob, g)
    assert np.array_equal(a.intersections, hits), "vectorized and loop intersections differ"
    assert np.allclose(a.distance, dist), "vectorized and loop distances differ"
    t = time.perf_counter()
    for _ in range(repeats):
        prob.assess(g)
    vec = repeats * pop / (time.perf_counter() - t)
    t = time.perf_counter()
    loop_assess(prob, g)
    loop = pop / (time.perf_counter() - t)
    print(f"{scenario}, population {pop}: vectorized {vec:,.0f} evaluations/s, "
          f"Python loop {loop:,.0f} evaluations/s, speed-up {vec / loop:.1f}x")
    return vec / loop


def success(seeds: int, matchings: list[str], wall: float, scenarios: list[str]) -> None:
    print("| scenario | matching | solved | median wall s | median CPU s | median generations |")
    print("|---|---|---|---|---|---|")
    for m in matchings:
        for name in scenarios:
            r = success_table(name, seeds, matching=m, wall_seconds=wall)
            print(f"| {name} | {m} | {r.solved}/{seeds} ({100 * r.rate:.0f}%) | "
                  f"{r.median_time_s:.2f} | {r.median_cpu_s:.2f} | "
                  f"{r.median_generations:.0f} |", flush=True)


ABLATIONS: dict[str, dict] = {
    "default": {},
    "greedy matching (paper)": {"matching": "greedy"},
    "assignment in chromosome": {"matching": "chromosome"},
    "no short-arc blend": {"circular_blend": False},
    "fixed 5 deg mutation": {"mutation_min_deg": 5.0, "mutation_max_deg": 5.0},
    "no restarts": {"restart_after": 0},
    "obstacle-aware distance": {"distance": "obstacle"},
    "survival with replacement (paper)": {"survival": "tournament"},
}
PAPER_LIKE = {"matching": "greedy", "circular_blend": False, "mutation_min_deg": 5.0,
             "mutation_max_deg": 5.0, "restart_after": 0, "survival": "tournament"}
ABLATIONS["paper-like (all five paper choices)"] = PAPER_LIKE
ABLATIONS["paper-like + optimal matching"] = {**PAPER_LIKE, "matching": "optimal"}
ABLATIONS["paper-like + restarts"] = {**PAPER_LIKE, "restart_after": 60}
ABLATIONS["paper-like + pairwise survival"] = {**PAPER_LIKE, "survival": "pairwise"}


def ablation(seeds: int, wall: float, scenarios: list[str], only: list[str] | None) -> None:
    """Success / median CPU time with one change at a time against the defaults."""
    print("| variant | scenario | solved | median CPU s | median generations |")
    print("|---|---|---|---|---|")
    for label, kw in ABLATIONS.items():
        if only and not any(o in label for o in only):
            continue
        for name in scenarios:
            pk, ak, _ = split_overrides(**kw)
            cfg, sched = ArmIKConfig(scenario=name, pictures=False, **pk), ScheduleConfig(**ak)
            cpu_t, gens, ok = [], [], 0
            for s in range(seeds):
                r = evolve(cfg, s, sched, wall, problem=ArmIKProblem(cfg))
                ok += r.solved
                cpu_t.append(r.time_to_solution_cpu_s if r.solved else np.inf)
                gens.append(r.generations)
            print(f"| {label} | {name} | {ok}/{seeds} | {np.median(cpu_t):.2f} | "
                  f"{np.median(gens):.0f} |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--part", choices=["speed", "success", "ablation", "all"], default="all")
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--matching", nargs="+", default=["optimal", "greedy"])
    ap.add_argument("--wall", type=float, default=30.0, help="budget per run (s)")
    ap.add_argument("--scenario", nargs="+",
                    default=[n for n in bundled_names() if n != "unreachable"])
    ap.add_argument("--variant", nargs="+", help="ablation variants whose label contains these")
    args = ap.parse_args()
    if args.part in ("speed", "all"):
        speed()
    if args.part in ("success", "all"):
        success(args.seeds, args.matching, args.wall, args.scenario)
    if args.part == "ablation":
        ablation(args.seeds, args.wall, args.scenario, args.variant)


if __name__ == "__main__":
    main()
