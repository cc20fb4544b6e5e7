"""NAO physics on a GPU (MuJoCo Warp) against ``mujoco.rollout`` on every CPU core (issue 18).

Measures, on one machine:

0. the host and device memory the run loop estimates (and checks) before allocating, for
   the step, walk and repertoire studies at population 1,024 ... 8,192;
1. NAO steps/s of one batch of standing NAOs (arms perturbed, feet in contact) at batch
   256 ... 8,192, ``problem.backend = "warp"`` (``WarpSimulator``, one captured CUDA graph per
   step) against ``mujoco.rollout`` with ``os.cpu_count()`` threads (``BatchSimulator``);
   also the largest batch with ``warp_deterministic = false``;
2. on the device: the largest state difference to ``mujoco.rollout`` over the first 0.5 s,
   whether a replay of the captured batch, a fresh simulator on the same batch, and the same
   trajectory at another row among other neighbours are bit-identical (what evaluators and
   resume would rely on; MuJoCo Warp 4.0.0 does not promise it on a GPU);
3. the wall time of ``evomotion run humanoid-step`` (its defaults: GA, 2 s step + 2 s hold =
   1,000 physics steps per rollout) at the paper's scale, population 100 x 100 generations,
   and at population 4,096, on warp and on cpu (run loop only: the ``wall_s`` of the last row
   of stats.csv). With ``--generations G < 100`` the figure is also given per generation and
   times 100 (marked "x100 from G");
4. the closed loop (issue 33): NAO steps/s of a population of standing NAOs under a linear
   balance-sized policy (28 observations: joint angles and velocities, gravity, gyro, foot
   contacts -> 10 joint offsets) acting every 20 ms (5 physics steps), at 1,024 ... 8,192
   worlds on the device (``WarpClosedLoopSimulator``), the policy evaluated on the device
   and, for comparison, on the host (numpy, a copy each way every control step), against the
   CPU closed loop (``ClosedLoopSimulator``, ``mujoco.rollout`` threads) at population 64.

Parts run in the order 0, 1, 2, 4, 3, and ``--out`` is rewritten after each, so a run cut
short by a time limit keeps what it measured.

Usage on a GPU machine (target: >= 1 M NAO steps/s on one H200-class GPU)::

    python benchmarks/bench_gpu.py --out gpu.json                 # everything (~15-20 min)
    python benchmarks/bench_gpu.py --generations 5 --out gpu.json # fits a 10-minute slot
    python benchmarks/bench_gpu.py --closed-loop-only --out cl.json  # part 4 alone (minutes)

Check on a machine without a GPU (Warp's CPU device; minutes)::

    python benchmarks/bench_gpu.py --device cpu --batches 8,16 --nstep 50 --generations 2 \\
        --pops 8 --cpu-batches 8,16
    python benchmarks/bench_gpu.py --device cpu --closed-loop-only --cl-batches 4,8 \\
        --cl-nstep 50 --cl-cpu-pop 8           # the closed-loop part alone

MuJoCo Warp and Warp come with ``pip install 'evomotion[gpu]'``. The benchmark prints one
table per part and writes every figure to ``--out`` (JSON).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from evomotion.sim.robots import nao  # noqa: E402
from evomotion.sim.rollout import BatchSimulator  # noqa: E402
from evomotion.sim.warp_rollout import WarpSimulator, import_warp  # noqa: E402


def controls(model, batch: int, nstep: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Standing NAOs, each with its own constant arm offsets (0.3 rad std): contacts at both
    feet all along, no falls (every step of every robot is simulated)."""
    rng = np.random.default_rng(seed)
    pose = nao.pose_vector()
    arms = np.array([n.startswith(("LShoulder", "RShoulder", "LElbow", "RElbow")) for n in
                     nao.JOINTS])
    offsets = rng.normal(0.0, 0.3, (batch, 1, model.nu)) * arms
    ctrl = np.broadcast_to(pose, (batch, nstep, model.nu)) + offsets
    return np.tile(nao.initial_state(model), (batch, 1)), np.ascontiguousarray(ctrl)


def timed(fn) -> tuple[float, object]:
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def physics(args, model, device: str) -> list[dict]:
    """Steps/s per batch in the run's mode (``--deterministic`` or not), the other mode at the
    largest batch; for each mode measured, whether replays, a fresh simulator and other
    neighbours give bit-identical states. Keys: ``warp`` = the mode asked for,
    ``warp_other`` = the other one (``mode`` / ``other_mode`` name them)."""
    rows = []
    cpu = BatchSimulator(model, args.threads or os.cpu_count())
    mode = lambda det: "deterministic" if det else "nondeterministic"  # noqa: E731
    for batch in args.batches:
        init, ctrl = controls(model, batch, args.nstep)
        row = {"batch": batch, "nstep": args.nstep, "mode": mode(args.deterministic)}
        dets = (args.deterministic,)
        if batch == max(args.batches) and not args.one_mode:
            dets = (args.deterministic, not args.deterministic)
            row["other_mode"] = mode(not args.deterministic)
        for det in dets:
            key = "warp" if det == args.deterministic else "warp_other"
            sim = WarpSimulator(model, device, deterministic=det)
            compile_s, first = timed(lambda s=sim: s.segment(init, ctrl))  # compile + capture
            wall, again = timed(lambda s=sim: s.segment(init, ctrl))
            row[f"{key}_steps_per_s"] = batch * args.nstep / wall
            row[f"{key}_first_call_s"] = compile_s
            row[f"{key}_replay_identical"] = bool(np.array_equal(first[0], again[0]))
            fresh = WarpSimulator(model, device, deterministic=det)
            other = fresh.segment(init, ctrl)[0]
            row[f"{key}_fresh_simulator_identical"] = bool(np.array_equal(other, again[0]))
            perm = np.roll(np.arange(batch), 1)  # row 0 moves to row 1, new neighbours
            moved = fresh.segment(init[perm], ctrl[perm])[0]
            row[f"{key}_batch_independent"] = bool(np.array_equal(moved[1], again[0][0]))
            fresh.close()
            if key == "warp":
                warp_states = again[0]
            sim.close()
        if batch in args.cpu_batches:
            cpu.run_with_sensors(init[:1], ctrl[:1, :10])  # threads started
            wall, (states, _) = timed(lambda: cpu.run_with_sensors(init[0], ctrl))
            row["cpu_steps_per_s"] = batch * args.nstep / wall
            early = min(125, args.nstep)
            diff = np.abs(states[:, :early, 1:] - warp_states[:, :early, 1:])
            nq = model.nq
            row["max_qpos_diff_first_0.5s"] = float(diff[..., :nq].max())
            row["max_qvel_diff_first_0.5s"] = float(diff[..., nq:nq + model.nv].max())
            row["speedup"] = row["warp_steps_per_s"] / row["cpu_steps_per_s"]
        rows.append(row)
        print(_fmt(row), flush=True)
    cpu.close()
    return rows


def _fmt(row: dict) -> str:
    return "  ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}"
                     for k, v in row.items())


def memory(args, device: str) -> list[dict]:
    """Host and device bytes the run loop estimates before allocating (its refusal check) for
    the step, walk and repertoire studies at their defaults on the warp backend."""
    from evomotion.run.config import resolve_config
    from evomotion.run.limits import memory_terms
    from evomotion.studies import get_study

    rows = []
    for name in ("humanoid-step", "humanoid-walk-open-loop", "humanoid-repertoire"):
        study = get_study(name)
        over = ["problem.backend=warp", f"problem.warp_device={device}"]
        cfg = resolve_config(study, None, over)
        seeded = getattr(cfg.problem, "with_run_seed", None)
        problem = study.make_problem(seeded(0) if seeded else cfg.problem)
        for pop in args.memory_pops:
            c = resolve_config(study, None, [*over, f"algorithm.pop_size={pop}"])
            host = sum(b for b, _ in memory_terms(c, problem))
            needed, free, _ = problem.device_memory(pop)
            rows.append({"study": name, "pop": pop, "host_GB": host / 1e9,
                         "device_GB": needed / 1e9,
                         "device_free_GB": free / 1e9 if free is not None else None})
            print(_fmt(rows[-1]), flush=True)
    return rows


def step_runs(args, device: str) -> list[dict]:
    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study
    from evomotion.run.stats import read_stats
    from evomotion.studies import get_study

    study = get_study("humanoid-step")
    rows = []
    for pop in args.pops:
        for backend in ("warp", "cpu"):
            if backend == "cpu" and pop > args.cpu_pop_max:
                continue
            over = [f"algorithm.pop_size={pop}", f"run.generations={args.generations - 1}",
                    "run.wall_seconds=0", f"problem.backend={backend}",
                    f"problem.warp_device={device}", "problem.batch_rollouts=8192",
                    f"problem.warp_deterministic={str(args.deterministic).lower()}"]
            with tempfile.TemporaryDirectory() as tmp:
                cfg = resolve_config(study, None, over)
                t0 = time.perf_counter()
                res = run_study(study, cfg, Path(tmp) / "run", quiet=True)
                total = time.perf_counter() - t0
                stats = read_stats(Path(tmp) / "run" / "stats.csv")
            loop = float(stats["wall_s"][-1])
            row = {"pop": pop, "generations": args.generations, "backend": backend,
                   "run_loop_s": loop, "with_finish_s": total, "s_per_generation":
                   loop / args.generations, "best": float(res.best_fitness)}
            if args.generations < 100:
                row[f"x100_from_{args.generations}_s"] = loop / args.generations * 100
            rows.append(row)
            print(_fmt(row), flush=True)
    return rows


def closed_loop(args, device: str) -> list[dict]:
    """Closed-loop NAO steps/s: device vs host policy on Warp, and the CPU closed loop."""
    from evomotion.core.policies import make_policy
    from evomotion.sim.closed_loop import ClosedLoopSimulator
    from evomotion.sim.observations import ObservationSpec
    from evomotion.sim.robots import load_robot
    from evomotion.sim.warp_closed_loop import WarpClosedLoopSimulator
    from evomotion.sim.warp_policy import PopulationPolicy

    robot = load_robot("nao")
    spec = ObservationSpec(("joint_pos", "joint_vel", "gravity", "gyro", "foot_contact"))
    k, nstep = 5, args.cl_nstep
    warp = WarpClosedLoopSimulator(robot, spec, k, device=device, deterministic=args.deterministic)
    nominal = np.asarray(robot.pose)[warp.columns]
    policy_spec = make_policy("linear", warp.observation_size, warp.action_size, scale=0.3,
                              low=warp.lower - nominal, high=warp.upper - nominal, clip_obs=5.0)
    rng = np.random.default_rng(0)

    def population(n: int) -> PopulationPolicy:
        return PopulationPolicy(policy_spec, 0.01 * rng.standard_normal((n, policy_spec.n_params)),
                                np.zeros(warp.observation_size), np.ones(warp.observation_size))

    def rate(sim, policy, n: int) -> tuple[float, float, int]:
        sim.run(policy, n, nstep)  # compile, then capture the graphs (CUDA)
        wall, res = timed(lambda: sim.run(policy, n, nstep))
        return float(res.steps.sum()) / wall, wall, int(res.fell.sum())

    rows = []
    for n in args.cl_batches:
        pol = population(n)
        dev, dev_wall, dev_fell = rate(warp, pol, n)
        host, host_wall, _ = rate(warp, lambda r, o, p=pol: p(r, o), n)
        rows.append({"worlds": n, "nstep": nstep, "control_steps": k,
                     "device_policy_steps_per_s": dev, "host_policy_steps_per_s": host,
                     "device_over_host": dev / host, "wall_device_s": dev_wall,
                     "fell": dev_fell})
        print(_fmt(rows[-1]), flush=True)
    pop = args.cl_cpu_pop
    with ClosedLoopSimulator(robot, spec, k, args.threads or os.cpu_count() or 1) as cpu:
        steps, wall, _ = rate(cpu, population(pop), pop)
    best = max(r["device_policy_steps_per_s"] for r in rows)
    rows.append({"cpu_closed_loop_pop": pop, "cpu_steps_per_s": steps, "cpu_wall_s": wall,
                 "best_device_over_cpu": best / steps})
    print(_fmt(rows[-1]), flush=True)
    return rows


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ints = lambda s: [int(v) for v in s.split(",") if v]  # noqa: E731
    p.add_argument("--device", default="", help="Warp device ('' = first GPU, else cpu)")
    p.add_argument("--batches", type=ints, default=[256, 512, 1024, 2048, 4096, 8192])
    p.add_argument("--cpu-batches", type=ints, default=[256, 1024, 4096, 8192])
    p.add_argument("--nstep", type=int, default=500, help="physics steps per rollout")
    p.add_argument("--threads", type=int, default=0, help="CPU threads (0 = all cores)")
    p.add_argument("--pops", type=ints, default=[100, 4096])
    p.add_argument("--cpu-pop-max", type=int, default=4096)
    p.add_argument("--generations", type=int, default=100)
    p.add_argument("--memory-pops", type=ints, default=[1024, 2048, 4096, 8192])
    p.add_argument("--skip-runs", action="store_true")
    p.add_argument("--only-memory", action="store_true")
    p.add_argument("--cl-batches", type=ints, default=[1024, 2048, 4096, 8192],
                   help="closed loop: worlds on the device")
    p.add_argument("--cl-nstep", type=int, default=500, help="closed loop: physics steps")
    p.add_argument("--cl-cpu-pop", type=int, default=64, help="closed loop: CPU population")
    p.add_argument("--closed-loop-only", action="store_true")
    p.add_argument("--deterministic", action="store_true",
                   help="MuJoCo Warp opt.deterministic for every part (off: the default)")
    p.add_argument("--one-mode", action="store_true",
                   help="physics: do not also measure the other mode at the largest batch")
    p.add_argument("--parts", default="memory,physics,closed_loop,runs",
                   help="comma-separated parts to run (memory, physics, closed_loop, runs)")
    p.add_argument("--out", default="")
    args = p.parse_args()
    wp, mjw = import_warp()
    from evomotion.sim.warp_rollout import resolve_device

    device = resolve_device(args.device)
    info = {"device": device, "deterministic": args.deterministic,
            "device_name": str(wp.get_device(device).name),
            "cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
            "warp": wp.__version__, "mujoco_warp": getattr(mjw, "__version__", "?"),
            "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}
    print(_fmt(info), flush=True)
    model = nao.load_model()
    result: dict = {"info": info}

    def save() -> None:  # after every part: a run cut short by its time limit keeps the rest
        if args.out:
            Path(args.out).write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")

    parts = {"closed_loop"} if args.closed_loop_only else set(args.parts.split(","))
    if args.only_memory:
        parts = {"memory"}
    if "memory" in parts:
        result["memory"] = memory(args, device)
        save()
        if args.only_memory and not args.out:
            print(json.dumps(result, indent=1))
    if "physics" in parts:
        result["physics"] = physics(args, model, device)
        save()
        best = max(r["warp_steps_per_s"] for r in result["physics"])
        print(f"peak warp NAO steps/s ({result['physics'][0]['mode']}): {best:,.0f} "
              "(target >= 1,000,000 on one H200-class GPU)", flush=True)
    if "closed_loop" in parts:
        result["closed_loop"] = closed_loop(args, device)
        save()
    if "runs" in parts and not args.skip_runs:
        result["humanoid_step_runs"] = step_runs(args, device)
        save()

if __name__ == "__main__":
    main()
