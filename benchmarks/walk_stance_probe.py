"""Would a stance with more sole behind the centre of mass catch backward pushes? A probe
(issue 34): the NAO's sole reaches 0.105 m in front of the walk's CoM and 0.055 m behind it,
and pushes from the front are the ones the walk survives least. The walk engine's ankles
moved forward of the torso (``OmniGait.x_offset_m``, 0 in the study) and its torso lean
(``lean_rad``, 0.05) changed, patched in this process only; then
``walk_capture_step.py``'s measure on the engine stepping in place in the nominal world, one
push per world: the plain engine and the engine with the capture step (the true velocity, an
oracle). Survival at each push size.

    python benchmarks/walk_stance_probe.py [--stances "0 0.05" "0.015 0.05" ...]
        [--worlds 60] [--pushes 2 3 4]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
import walk_capture_step  # noqa: E402
from evomotion.studies.humanoid_omniwalk import problem as problem_module  # noqa: E402
from markdown_table import markdown_row, markdown_table  # noqa: E402

ORIGINAL = problem_module.OmniWalkConfig.gait
STANCE = {"x_offset_m": 0.0, "lean_rad": 0.05}


def gait(self):
    return dataclasses.replace(ORIGINAL(self), **STANCE)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--stances", nargs="+", default=["0 0.05", "0.015 0.05", "0.03 0.05",
                                                     "0 0", "0.03 0"],
                    help="'x_offset_m lean_rad' pairs")
    ap.add_argument("--worlds", type=int, default=60)
    ap.add_argument("--duration", type=float, default=6.0)
    ap.add_argument("--pushes", type=float, nargs="+", default=[2.0, 3.0, 4.0])
    ap.add_argument("--seed", type=int, default=7)
    a = ap.parse_args()
    problem_module.OmniWalkConfig.gait = gait  # type: ignore[method-assign]
    rows = []
    for stance in a.stances:
        x, lean = (float(v) for v in stance.split())
        STANCE.update(x_offset_m=x, lean_rad=lean)
        for r in walk_capture_step.measure(a.worlds, a.duration, a.pushes, [0.48], 1.0, a.seed):
            rows.append([f"{x:g}", f"{lean:g}", *r[1:]])
            print(markdown_row(rows[-1]), flush=True)
    print(f"\n{a.worlds} worlds x {a.duration:g} s, nominal world, stepping in place\n")
    print(markdown_table(["x_offset_m", "lean_rad", "who"] + [f"{p:g} N s" for p in a.pushes],
                         rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
