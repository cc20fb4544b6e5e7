"""What the walk's capture step (``problem.capture_gain``) costs: one evaluation of the NAO
default's population (33 controllers x 2 episodes of 8 s, perturbed pushed worlds, the fitted
start plus noise) with the layer (gain 1) and without (gain 0), back to back, best of
``--repeat``; and one call of the standard-library layer the NAOqi runner and the policy
player run (``sim/robots/nao/naoqi_capture_step.py``), per control step of one robot.

    python benchmarks/capture_step_cost.py [--repeat 3] [--threads 2]
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np

from evomotion.run.config import resolve_config
from evomotion.sim.robots.nao.naoqi_capture_step import CaptureStep
from evomotion.studies import get_study
from evomotion.studies.humanoid_omniwalk.artifacts import capture_step_record, policy_info
from evomotion.studies.humanoid_omniwalk.problem import OmniWalkProblem


def evaluation_s(gain: float, threads: int, repeat: int) -> float:
    cfg = resolve_config(get_study("humanoid-walk"), None, []).problem
    p = OmniWalkProblem(replace(cfg, capture_gain=gain, threads=threads))
    x = p.policy_params(p.initial_population(None, np.random.default_rng(0)))
    n = 66
    params = x + 0.005 * np.random.default_rng(1).standard_normal((n, x.shape[1]))
    mean, std = np.zeros((n, p.obs_dim)), np.ones((n, p.obs_dim))
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        p.play(params, mean, std, np.arange(n))
        best = min(best, time.perf_counter() - t)
    p.sim.close()
    return best


def layer_call_ms(calls: int = 2000) -> float:
    cfg = resolve_config(get_study("humanoid-walk"), None, []).problem
    p = OmniWalkProblem(replace(cfg, threads=1))
    info = policy_info(p)
    layer = CaptureStep(capture_step_record(p.ctl, 1.0), list(p.obs_names), info["joints"],
                        info["nominal_rad"], p.ctl.control_dt)
    obs = np.random.default_rng(2).normal(0, 0.3, (calls, p.obs_dim)).tolist()
    act = [0.0] * p.act_dim
    t = time.perf_counter()
    for o in obs:
        layer(o, act)
    return (time.perf_counter() - t) / calls * 1e3


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    plain = evaluation_s(0.0, a.threads, a.repeat)
    layer = evaluation_s(1.0, a.threads, a.repeat)
    print("| capture_gain | one evaluation (66 episodes x 8 s), s |")
    print("|---|---|")
    print(f"| 0 | {plain:.2f} |\n| 1 | {layer:.2f} |")
    print(f"ratio gain 1 / gain 0: {layer / plain:.2f}")
    print(f"standard-library layer: {layer_call_ms():.3f} ms per call (one robot, one step)")


if __name__ == "__main__":
    main()
