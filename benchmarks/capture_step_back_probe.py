"""Do backward pushes need a longer backward capture step? A probe on a humanoid-walk run
with capture steps: its layer's backward velocity offset (``Δv_x < 0``, eq. (2) of
``studies/humanoid_omniwalk/capture_step.py``) scaled by ``k`` (the velocity the layer reads
moved by ``(k - 1) min(Δv_x, 0)``: the calibration gate and the dead band see the scaled
offset too) and the layer's reach ``REACH_X_M`` set, both patched in this process only;
then ``walk_falls.py``'s measurement (the same 100 worlds x 60 s as ``compare``, by push
size and direction). The first variant, ``1 0.10``, is the run as it is.

    python benchmarks/capture_step_back_probe.py RUN [--variants "1 0.10" "2 0.10" ...]
        [--worlds 100] [--duration 60]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from evomotion.studies.humanoid_omniwalk import capture_step  # noqa: E402
from walk_falls import measure, table  # noqa: E402

ORIGINAL = capture_step.CaptureStep.velocity_of


def patch(k: float, reach_m: float) -> None:
    def velocity_of(self, rows, obs, phase):
        v = ORIGINAL(self, rows, obs, phase)
        b = np.round(phase * self.bins).astype(np.int64) % self.bins
        back = np.minimum(v[:, 0] - obs[:, self.ic[0]] - self.sway[rows, b, 0], 0.0)
        return np.stack([v[:, 0] + (k - 1.0) * back, v[:, 1]], axis=1)

    capture_step.CaptureStep.velocity_of = velocity_of  # type: ignore[method-assign]
    capture_step.REACH_X_M = reach_m


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run")
    ap.add_argument("--variants", nargs="+", default=["1 0.10", "2 0.10", "2 0.14"])
    ap.add_argument("--worlds", type=int, default=100)
    ap.add_argument("--duration", type=float, default=60.0)
    a = ap.parse_args()
    for v in a.variants:
        k, reach = (float(x) for x in v.split())
        patch(k, reach)
        print(f"backward offset x{k:g}, reach {reach:g} m:")
        print(table(measure(a.run, a.worlds, a.duration, 0)), "\n", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
