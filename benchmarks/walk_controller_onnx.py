"""Does the exported ``controller.onnx`` walk as the controller evomotion trained and measured?
A humanoid-walk run with capture steps, played twice on ``humanoid-walk compare``'s unseen
perturbed worlds under their random command schedules and pushes: by evomotion's numpy policy
and capture-step layer (as ``compare``), and by onnxruntime running the run's
``controller.onnx`` (the policy and the layer in one graph, its state fed back every control
period, float32 observations in and actions out; built from the run's ``policy.npz`` as the
exporter does where the folder predates the file). Survival, time up, the tracking errors, and
how many worlds end the same way (both up or both fallen); the two differ only by the graph's
float32 input and output rounding (about 1e-8 rad per step), which a chaotic fall can grow.

    python benchmarks/walk_controller_onnx.py RUN [RUN ...] [--worlds 100] [--duration 60]

Also the time of one ``controller.onnx`` call for one robot (the median of ``--calls`` calls on
the first world's observations, onnxruntime's CPU provider, one intra-op thread).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from evomotion.studies.humanoid_omniwalk import controller as controller_module  # noqa: E402
from markdown_table import markdown_row, markdown_table  # noqa: E402
from walk_deployed_sensing import tracking_cells  # noqa: E402

ORIGINAL = controller_module.Controller.run
SESSION: list = [None]  # the onnxruntime session while the ONNX rows play
SEEN: list = []  # the first world's observations while the ONNX rows play


def onnx_run(self, params, mean, std, worlds, nstep, commands):
    """``Controller.run`` with ``controller.onnx`` as the whole controller (``SESSION[0]``)."""
    sess = SESSION[0]
    if sess is None:
        return ORIGINAL(self, params, mean, std, worlds, nstep, commands)
    state = np.zeros((len(params), sess.get_inputs()[1].shape[1]))

    def policy(rows, obs):
        if len(SEEN) < 3000:
            SEEN.extend(obs[rows == 0])
        act, state[rows] = sess.run(None, {"observation": obs.astype(np.float32),
                                           "state_in": state[rows]})
        return act.astype(np.float64)

    return self.sim.run(policy, worlds, nstep, commands=commands, initial_state=self.state0,
                        record_states=True, record_targets=True)


def session(run: Path, problem, threads: int = 0):
    import onnxruntime as ort

    path = run / "controller.onnx"
    if path.is_file():
        data = path.read_bytes()
    else:  # a run from before controller.onnx: the exporter's own build
        from evomotion.core.policies.export import read_policy_npz
        from evomotion.studies.humanoid_omniwalk.artifacts import controller_onnx

        data = controller_onnx(problem, read_policy_npz(run / "policy.npz")).SerializeToString()
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = threads
    return ort.InferenceSession(data, opts, providers=["CPUExecutionProvider"])


def call_time_ms(sess, obs: np.ndarray, calls: int) -> float:
    """The median time (ms) of one call for one robot, ``obs[k % len(obs)]`` in turn."""
    import time

    state, times = np.zeros((1, sess.get_inputs()[1].shape[1])), []
    x = obs.astype(np.float32)
    for k in range(calls):
        t = time.perf_counter()
        _, state = sess.run(None, {"observation": x[k % len(x)][None], "state_in": state})
        times.append(time.perf_counter() - t)
    return 1e3 * float(np.median(times))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="+", type=Path)
    ap.add_argument("--worlds", type=int, default=100)
    ap.add_argument("--duration", type=float, default=60.0)
    ap.add_argument("--calls", type=int, default=2000)
    a = ap.parse_args()
    from evomotion.studies.humanoid_omniwalk.compare import (
        EVAL_SEED_BASE,
        _play,
        _summary,
        load_run,
    )

    controller_module.Controller.run = onnx_run  # type: ignore[method-assign]
    head = ["run", "controller", "survival", "time up (s)", "speed error: every window / "
            "steady", "yaw-rate error: every window / steady", "same end"]
    rows = []
    for run in a.runs:
        problem, pol, _ = load_run(run, a.duration)
        if not problem.cfg.capture_gain:
            ap.error(f"{run}: no capture steps (problem.capture_gain 0): no controller.onnx")
        seeds = EVAL_SEED_BASE + np.arange(a.worlds)
        ends = []
        for name, sess in (("numpy (evomotion)", None), ("controller.onnx", session(run,
                                                                                    problem))):
            SESSION[0] = sess
            m = _play(problem, pol.params, pol.obs_mean, pol.obs_std, seeds)
            s, up = _summary(m), m["survived"] >= 1
            ends.append(up)
            same = f"{np.mean(ends[0] == up):.0%}" if len(ends) == 2 else ""
            rows.append([str(run), name, f"{s['survival']:.0%}", f"{s['time_up_s']:.1f}",
                         *tracking_cells(s), same])
            print(markdown_row(rows[-1]), flush=True)
        SESSION[0] = None
        obs = np.array(SEEN)
        SEEN.clear()
        print(f"{run}: one call of controller.onnx for one robot "
              f"{call_time_ms(session(run, problem, 1), obs, a.calls):.3f} ms (median of "
              f"{a.calls})", flush=True)
        problem.sim.close()
    print(f"\n{a.worlds} worlds x {a.duration:g} s, the run's pushes, random commands\n")
    print(markdown_table(head, rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
