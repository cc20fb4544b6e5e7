"""The sole/floor contact model measured against Webots' own NAO motions (issue 13, part 0).

Replays every fixture of ``tests/fixtures/webots-motions`` (1 s hold) on the NAO model with
the sole contact replaced by each candidate (condim, torsional and rolling friction) and
prints, per candidate, the heading change and displacement of each motion and the error of the
heading against the motion's name (TurnLeft40: +40 deg, TurnRight40: -40 deg, TurnLeft60:
+60 deg, the others: 0), plus the worst and mean absolute heading error.

    python benchmarks/contact_model.py
"""

from __future__ import annotations

import math
from pathlib import Path

from evomotion.sim.motion import read_motion
from evomotion.sim.robots.nao import model as nao_model
from evomotion.sim.robots.nao import replay as nao_replay

FIXTURES = Path(__file__).resolve().parents[1] / "tests" / "fixtures" / "webots-motions"
INTENT_DEG = {"TurnLeft40": 40.0, "TurnLeft60": 60.0, "TurnRight40": -40.0,
              "SideStepLeft": 0.0, "SideStepRight": 0.0, "HandWave": 0.0, "Shoot": 0.0}
FOOT = 'condim="4"\n            friction="0.7 0.02 0.0001" solref="0.008 1"/>'
CANDIDATES = {  # label -> the foot class's contact attributes
    "condim 3 (friction 0.7, torsional unused)": 'condim="3"\n            '
                                                 'friction="0.7 0.005 0.0001" solref="0.008 1"/>',
    "condim 4, torsional 0.005": 'condim="4"\n            friction="0.7 0.005 0.0001" '
                                 'solref="0.008 1"/>',
    "condim 4, torsional 0.02 (chosen)": FOOT,
    "condim 4, torsional 0.03": 'condim="4"\n            friction="0.7 0.03 0.0001" '
                                'solref="0.008 1"/>',
    "condim 6, torsional 0.02, rolling 0.0001": 'condim="6"\n            '
                                                'friction="0.7 0.02 0.0001" solref="0.008 1"/>',
    "condim 6, torsional 0.02, rolling 0.001": 'condim="6"\n            '
                                               'friction="0.7 0.02 0.001" solref="0.008 1"/>',
}


def main() -> None:
    base = nao_model.MODEL_PATH.read_text()
    if FOOT not in base:
        raise SystemExit("the model's foot contact is not the expected text; update FOOT")
    original = nao_model.model_xml
    print("| contact | " + " | ".join(INTENT_DEG) + " | worst / mean abs heading error |")
    print("|---|" + "---|" * (len(INTENT_DEG) + 1))
    try:
        for label, attrs in CANDIDATES.items():
            xml = base.replace(FOOT, attrs)
            nao_model.model_xml = lambda x=xml: x  # replay loads the model through this
            cells, errs = [], []
            for name, want in INTENT_DEG.items():
                s = nao_replay.simulate_motion(read_motion(FIXTURES / f"{name}.motion"),
                                               hold_s=1.0)["summary"]
                h = math.degrees(s["heading_change_rad"])
                dx, dy = s["displacement_m"]
                errs.append(abs(h - want))
                cells.append(f"{h:+.1f}° ({h - want:+.1f}), {dx:+.3f}/{dy:+.3f} m"
                             + (", FELL" if s["fell"] else ""))
            print(f"| {label} | " + " | ".join(cells)
                  + f" | {max(errs):.1f}° / {sum(errs) / len(errs):.2f}° |", flush=True)
    finally:
        nao_model.model_xml = original


if __name__ == "__main__":
    main()
