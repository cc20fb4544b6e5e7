"""Closed-loop rollout throughput against the open-loop ``mujoco.rollout`` path (issue 33).

The NAO, a population of 64, the same physics steps (2 s at the model's 4 ms step, no early
stop: nobody falls under these small targets) and the same thread count: open loop
(:class:`evomotion.sim.rollout.BatchSimulator`, controls precomputed, one call) against the
closed loop (:class:`evomotion.sim.closed_loop.ClosedLoopSimulator`, a linear policy on
joint angles and velocities, IMU, foot contacts and gait phase) with a control step every 2,
3 and 5 physics steps (8, 12 and 20 ms; 10 ms is not a whole number of 4 ms steps). Runs
alternate and the best of ``--repeat`` is kept (the machine is shared). ``rollout share``: the
closed loop's wall time inside ``mujoco.rollout``; the rest is the per-control-step overhead
(observations, policy, FIFO, state copies). Steps per CPU second (the process's CPU time, both
threads) are printed beside the wall-clock figures: they suffer less from a shared machine.

    python benchmarks/bench_closed_loop.py [--pop 64] [--threads 2] [--seconds 2] [--repeat 5]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from evomotion.sim.closed_loop import ClosedLoopSimulator
from evomotion.sim.observations import ObservationSpec
from evomotion.sim.robots import load_robot
from evomotion.sim.rollout import BatchSimulator

SPEC = ObservationSpec(("joint_pos", "joint_vel", "gravity", "gyro", "foot_contact", "phase"),
                       phase_period_s=0.5)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pop", type=int, default=64)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--periods", type=int, nargs="+", default=[2, 3, 5])
    a = ap.parse_args()
    robot = load_robot("nao")
    nstep = int(round(a.seconds / robot.model.opt.timestep))
    rng = np.random.default_rng(0)
    t = robot.model.opt.timestep * np.arange(nstep)
    ctrl = np.broadcast_to(robot.pose, (a.pop, nstep, robot.model.nu)).copy()
    ctrl[:, :, robot.columns] += 0.02 * np.sin(2 * np.pi * t / 0.5)[None, :, None]
    open_loop = BatchSimulator(robot.model, a.threads)
    sims = {k: ClosedLoopSimulator(robot, SPEC, k, a.threads, fall_height_m=-np.inf,
                                   fall_tilt_rad=np.pi) for k in a.periods}
    gain = 0.01 * rng.standard_normal((a.pop, sims[a.periods[0]].action_size,
                                       sims[a.periods[0]].observation_size))

    def policy(rows: np.ndarray, obs: np.ndarray) -> np.ndarray:
        return np.einsum("nao,no->na", gain[rows], obs)

    best = {"open": np.inf} | {k: np.inf for k in a.periods}
    cpu = dict.fromkeys(best, np.inf)  # process CPU seconds (all threads): less noisy
    share = {k: 0.0 for k in a.periods}
    for _ in range(a.repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        open_loop.run(robot.state0, ctrl)
        best["open"] = min(best["open"], time.perf_counter() - t0)
        cpu["open"] = min(cpu["open"], time.process_time() - c0)
        for k, sim in sims.items():
            sim.rollout_seconds = 0.0
            t0, c0 = time.perf_counter(), time.process_time()
            res = sim.run(policy, a.pop, nstep)
            wall = time.perf_counter() - t0
            cpu[k] = min(cpu[k], time.process_time() - c0)
            assert int(res.steps.sum()) == a.pop * nstep and not res.fell.any()
            if wall < best[k]:
                best[k], share[k] = wall, sim.rollout_seconds / wall
    steps = a.pop * nstep
    print(f"NAO pop={a.pop} threads={a.threads} physics steps={steps} "
          f"({nstep} per robot, dt={robot.model.opt.timestep} s), best of {a.repeat}")
    print("| path | control period | physics steps/s (wall) | ratio | steps per CPU s | "
          "ratio | rollout share |")
    print("|---|---|---|---|---|---|---|")
    print(f"| open loop (precomputed) | - | {steps / best['open']:,.0f} | 1.00 | "
          f"{steps / cpu['open']:,.0f} | 1.00 | - |")
    for k in a.periods:
        ms = 1000 * k * robot.model.opt.timestep
        print(f"| closed loop (linear) | {ms:g} ms ({k} steps) | {steps / best[k]:,.0f} | "
              f"{best['open'] / best[k]:.2f} | {steps / cpu[k]:,.0f} | "
              f"{cpu['open'] / cpu[k]:.2f} | {share[k]:.2f} |")
    open_loop.close()
    for sim in sims.values():
        sim.close()


if __name__ == "__main__":
    main()
