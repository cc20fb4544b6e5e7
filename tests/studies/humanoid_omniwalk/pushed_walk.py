"""One pushed simulated walk with the capture step, as the layer saw it: the stream the
capture-step tests (numpy, standard library, ONNX) compare their layers on."""

from __future__ import annotations

import numpy as np

from evomotion.studies.humanoid_omniwalk.capture_step import CaptureStep
from evomotion.studies.humanoid_omniwalk.problem import OmniWalkConfig, OmniWalkProblem


def pushed_walk(seconds: float = 4.0):
    """(problem, observations [C, O] the layer saw, the policy's actions [C, A]) of one pushed
    episode (3 N s, world seed 3) of the fitted controller with the capture step (gain 1.5)."""
    p = OmniWalkProblem(OmniWalkConfig(duration_s=seconds, threads=1, capture_gain=1.5,
                                       push_min_ns=3.0, push_max_ns=3.0,
                                       command_feedback=True, command_feedback_start=0.1))
    seen: list[tuple[np.ndarray, np.ndarray]] = []
    real = CaptureStep.__call__

    def spy(self, rows, obs, action):
        seen.append((obs[0].copy(), action[0].copy()))
        return real(self, rows, obs, action)

    CaptureStep.__call__ = spy
    try:
        p.play(p.ctl.initial_params()[None], np.zeros((1, p.obs_dim)),
               np.ones((1, p.obs_dim)), np.array([3]))
    finally:
        CaptureStep.__call__ = real
    p.sim.close()
    return p, np.array([o for o, _ in seen]), np.array([a for _, a in seen])


def fuzzed(names: list[str], obs: np.ndarray, rng: np.random.Generator, k: int) -> np.ndarray:
    """The stream made harder, its ``k``-th time over: joint velocities with noise of
    ``0.5 + k`` rad/s, random contacts and commands, the phase jittered by 0.05 rad (clips,
    the lift-off blend and the phase bin's rounding exercised)."""
    vel = [i for i, n in enumerate(names) if n.startswith("joint_vel:")]
    contact = [names.index("foot_contact:left"), names.index("foot_contact:right")]
    command = [names.index(f"command:{i}") for i in range(3)]
    ph = names.index("phase:sin"), names.index("phase:cos")
    o = obs.copy()
    o[:, vel] += rng.normal(0, 0.5 + k, (len(o), len(vel)))
    o[:, contact] = rng.random((len(o), 2)) < 0.6
    o[:, command] = rng.uniform([-0.2, -0.2, -1.2], [0.45, 0.2, 1.2], (len(o), 3))
    angle = np.arctan2(o[:, ph[0]], o[:, ph[1]]) + rng.normal(0, 0.05, len(o))
    o[:, ph[0]], o[:, ph[1]] = np.sin(angle), np.cos(angle)
    return o
