"""A controller trained with steps at once after pushes (issue 34): ``humanoid-walk``'s
default (capture steps) with a detector in the loop. Every control period the capture-step
layer's own velocity offset ``Δv`` (eq. (2) of ``studies/humanoid_omniwalk/capture_step.py``,
before its dead band) is read; past ``--tau`` m/s (after the layer's warm-up, at most once
per ``--refractory`` s) the gait clock jumps to the start of the next step (the swinging foot
lands now, the other lifts; ``step_now_probe.py`` is the untrained oracle). The clock is the
controller's own from then on (the policy and the layer read it). Patched into
``Controller.run`` in this process for the training (``evomotion.api.run``, the study's
defaults, ``--seed``) and for the measurement after it (``walk_falls.py``'s: ``compare``'s 100
worlds x 60 s, by push size and direction).

    python benchmarks/step_now_train.py OUT [--seed 0] [--tau 0.45] [--refractory 0.5]
    python benchmarks/step_now_train.py OUT --measure-only      # a run made by this script
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from evomotion.studies.humanoid_omniwalk import capture_step as cs  # noqa: E402
from evomotion.studies.humanoid_omniwalk import controller as controller_module  # noqa: E402
from step_now_probe import clocked_run  # noqa: E402
from walk_falls import measure, table  # noqa: E402

SETTINGS = {"tau": 0.45, "refractory_s": 0.5}


def detector(worlds, layer):
    """Fires where the layer's ``|Δv|`` passes ``SETTINGS["tau"]`` (module doc)."""
    last = np.full(len(worlds), -10 ** 6)
    refract = int(round(SETTINGS["refractory_s"] / layer.ctl.control_dt))

    def fire(rows, o, count):
        ph = layer.phase(o)
        b = np.round(ph * layer.bins).astype(np.int64) % layer.bins
        dv = layer.velocity_of(rows, o, ph) - o[:, layer.ic[:2]] - layer.sway[rows, b]
        dv = np.where(np.isfinite(dv), dv, 0.0)
        warm = layer.steps[rows] + 1 > cs.WARMUP_CYCLES * layer.bins
        hit = warm & (np.linalg.norm(dv, axis=1) > SETTINGS["tau"]) & \
            (count[rows] - last[rows] > refract)
        last[rows[hit]] = count[rows[hit]]
        return hit

    return fire


def run(self, params, mean, std, worlds, nstep, commands):
    """``Controller.run`` with the detector's clock (module doc)."""
    return clocked_run(self, detector)(params, mean, std, worlds, nstep, commands)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--tau", type=float, default=0.45)
    ap.add_argument("--refractory", type=float, default=0.5)
    ap.add_argument("--measure-only", action="store_true")
    a = ap.parse_args()
    SETTINGS.update(tau=a.tau, refractory_s=a.refractory)
    controller_module.Controller.run = run  # type: ignore[method-assign]
    if not a.measure_only:
        from evomotion.api import run as run_study

        r = run_study("humanoid-walk", {"run": {"seed": a.seed}}, a.out)
        print(f"{a.out}: {r.stop_reason} at generation {r.generation}", flush=True)
    print(table(measure(str(a.out), 100, 60.0, 0)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
