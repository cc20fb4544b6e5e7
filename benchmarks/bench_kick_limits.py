"""What limits a kick's distance (issue 34, item 3): one straight kick of a biped-kick run,
measured at the moment the foot meets the ball, on the calibrated carpet.

Printed per kick (the run's best genome, aim 0, the nominal ball place):

- **motor speed**: the largest commanded joint speed of the 20 ms key poses over the no-load
  speed (the constraint ``speed_ratio``), and the simulated joint speeds of the kicking leg at
  impact over the same no-load speeds (the simulated servos have no speed limit of their own);
- **ZMP**: the smallest centre-of-pressure margin during the kick (the constraint: >= 5 mm);
- **impact**: the kicking foot's speed just before contact, the ball's speed just after (their
  ratio is the impact's speed gain: 1 for a perfectly inelastic hit, 2 for an elastic one on a
  much heavier foot), the ball's speed once it rolls without slipping (a solid ball hit at its
  centre's height keeps 5/7 of its speed), and the distance rolled;
- **sensitivity**: the same search re-run with the motors' speed limit scaled by ``--margins``
  (``problem.speed_margin``): how the distance follows the motor speed.

    python benchmarks/bench_kick_limits.py RUN_DIR [--margins 0.8 0.9] [--budget 2000]
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import mujoco
import numpy as np

from evomotion.core.cmaes import CMAESConfig
from evomotion.run.config import Config, RunSection
from evomotion.run.in_memory import run_in_memory
from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.joint_limits import SPEED_LIMITS
from evomotion.studies.biped_kick import scene
from evomotion.studies.biped_kick.play import read_kick
from evomotion.studies.biped_kick.problem import KickConfig, KickProblem

LEG = ("RHipPitch", "RKneePitch", "RAnklePitch")


def impact(problem: KickProblem, genome: np.ndarray) -> dict[str, float]:
    m, dt = problem.model, problem.dt
    g = genome[None]
    aims = np.zeros(1)
    k = problem.kicks(g, aims, problem.ball_xy(g, aims), keep=True)
    st = k["states"][0]
    iv = scene.ball_qvel_index(m)
    v = st[:, 1 + m.nq + iv: 1 + m.nq + iv + 3]  # state = time, qpos, qvel
    w_local = st[:, 1 + m.nq + iv + 3: 1 + m.nq + iv + 6]  # a free joint's: body frame
    iq = scene.ball_qpos_index(m)
    w = np.empty_like(w_local)
    for t in range(len(st)):
        rot = np.empty(9)
        mujoco.mju_quat2Mat(rot, st[t, 1 + iq + 3: 1 + iq + 7])
        w[t] = rot.reshape(3, 3) @ w_local[t]
    speed = np.linalg.norm(v[:, :2], axis=1)
    hit = int(np.argmax(speed > 0.02))
    launch_i = hit + int(np.argmax(speed[hit:hit + 50]))
    slip = np.linalg.norm(v[:, :2] + np.cross(w, [0, 0, -scene.BALL_RADIUS_M])[:, :2], axis=1)
    rolling = slip[launch_i:] < 0.02 * np.maximum(speed[launch_i:], 0.05)
    rolling_i = launch_i + (int(np.argmax(rolling)) if rolling.any() else len(rolling) - 1)
    d = mujoco.MjData(m)
    foot = []
    for t in (hit - 2, hit - 1):
        mujoco.mj_setState(m, d, st[t], nao.STATE_SPEC)
        mujoco.mj_kinematics(m, d)
        foot.append(d.site("r_sole_site").xpos[:2].copy())
    foot_speed = float(np.linalg.norm(foot[1] - foot[0]) / dt)
    qv = {j: abs(float(st[hit - 1, 1 + m.nq + nao.qvel_address(m, j)])) / SPEED_LIMITS[j]
          for j in LEG}
    return {"distance_m": float(k["along_m"][0]), "speed_ratio_keys": float(k["speed_ratio"][0]),
            "min_zmp_margin_mm": 1e3 * float(k["min_margin_m"][0]),
            "foot_speed_m_s": foot_speed, "ball_launch_m_s": float(speed[launch_i]),
            "ball_rolling_m_s": float(speed[rolling_i]),
            "slide_s": (rolling_i - launch_i) * dt,
            **{f"{j}_speed_ratio": r for j, r in qv.items()}}


def rerun(cfg: KickConfig, margin: float, budget: int, seed: int) -> tuple[float, float]:
    c = dataclasses.replace(cfg, speed_margin=margin, aims_deg=(0.0,))
    problem = KickProblem(c)
    run = RunSection(seed=seed, generations=10**9, max_evaluations=budget, checkpoint_every=0)
    t0 = time.perf_counter()
    res = run_in_memory(Config("biped-kick", run, CMAESConfig(sigma0=0.15), c), problem)
    return impact(problem, np.asarray(res.best_genome))["distance_m"], time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("run", type=Path)
    ap.add_argument("--margins", type=float, nargs="*", default=[])
    ap.add_argument("--budget", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    genome, _ = read_kick(args.run)
    cfg = KickConfig()
    r = impact(KickProblem(dataclasses.replace(cfg, aims_deg=(0.0,))), genome)
    print("| quantity | value |\n|---|---|")
    for key, val in r.items():
        print(f"| {key} | {val:.3f} |")
    print(f"| impact speed gain (ball / foot) | {r['ball_launch_m_s'] / r['foot_speed_m_s']:.2f} |")
    print(f"| kept after sliding (rolling / launch) | "
          f"{r['ball_rolling_m_s'] / r['ball_launch_m_s']:.2f} |")
    if args.margins:
        print("\n| motor speed limit (x no-load) | straight distance (m) | search (s) |\n"
              "|---|---|---|")
        for mg in [1.0, *args.margins]:
            dist, secs = rerun(cfg, mg, args.budget, args.seed)
            print(f"| {mg:.2f} | {dist:.2f} | {secs:.0f} |")


if __name__ == "__main__":
    main()
