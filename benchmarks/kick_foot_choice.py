"""Which foot should kick at which aim (issue 34)? The calibrated kick (the adaptive kick, its
swing slowed and its foot rolled in the air where needed, and its commanded aim from the aim
table, as ``kick_adapt.py``'s third column)
with the right foot and with the left one (the right kick in mirror image) at each aim, on
kick_adapt's two draws of 100 ball offsets U(+-2 cm) and perturbed worlds (seeds 12345 / 2026
and 7 / 8): share within +-10 deg, falls, mean distance along the aim.

    python benchmarks/kick_foot_choice.py --table T.json [--aims -20 -15 -10 0 10 15 20]

``--table``: an aim table of the shipped kick (``kick_adapt.py --table`` or ``evomotion
biped-kick calibrate``; measured anew when the file does not exist, about 4 min).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from evomotion.studies.biped_kick import aim_table
from evomotion.studies.biped_kick.experiment import accuracy, kick_draw, perturbed_kicks
from evomotion.studies.biped_kick.play import read_kick
from evomotion.studies.biped_kick.problem import KickConfig, KickProblem

DRAWS = ((12345, 2026), (7, 8))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--table", type=Path, required=True)
    ap.add_argument("--aims", type=float, nargs="+",
                    default=[-30, -20, -15, -10, 0, 10, 15, 20, 30])
    args = ap.parse_args()
    genome, source = read_kick(None)
    problem = KickProblem(KickConfig())
    table = aim_table.read_or_measure(args.table, problem, genome, str(source))
    t0 = time.perf_counter()
    print(f"kick: {source}\n| aim (deg) | draw | right: within +-10 deg | falls | distance (m) "
          "| left: within +-10 deg | falls | distance (m) |\n|---|---|---|---|---|---|---|---|")
    for a in args.aims:
        for seeds in DRAWS:
            offsets, worlds = kick_draw(problem, 100, seeds)
            cells = []
            for left in (False, True):
                r = accuracy(perturbed_kicks(problem, genome, offsets, a, worlds, adapt=True,
                                             left_foot=left, table=table))
                cells.append(f"{r['within_10deg']:.0%} | {r['fall_rate']:.0%} | "
                             f"{r['mean_distance_m']:.2f}")
            print(f"| {a:+g} | {seeds[0]}, {seeds[1]} | {cells[0]} | {cells[1]} |", flush=True)
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    from evomotion.errors import InputError

    try:
        main()
    except InputError as e:  # a bad table: one line
        raise SystemExit(f"error: {e}") from None
