"""``evomotion humanoid-walk-open-loop compare``: an evolved walk beside Webots' own NAO motions.

Every motion is replayed open loop on the same model and contact (``evomotion replay``):
the walk (``best.motion`` of a run folder, or any ``.motion``) and the step and turn motions
Webots ships for its NAO (package data, Apache-2.0; Webots' ``Forwards50.motion`` is not among
the fixtures this project has). For each: duration, displacement, heading change, speed
(forward displacement over the motion's duration), heading change per metre (for motions that
move at least 5 cm forward) and whether it fell. ``--trials N`` adds the fall rate in N
perturbed worlds (:mod:`evomotion.sim.worlds`, default ranges) for each motion.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from evomotion.errors import InputError
from evomotion.sim.motion import Motion, read_motion
from evomotion.sim.robots.nao.replay import StressOptions, simulate_motion, stress_motion
from evomotion.sim.robots.nao.webots_motions import SHIPPED_MOTIONS, shipped_motion

WEBOTS = tuple(m for m in SHIPPED_MOTIONS if m != "Shoot")
#: heading per metre is reported only for motions that move at least this far forward (m)
MIN_DISTANCE_M = 0.05


def walk_motion_path(run: Path) -> Path:
    """``run/best.motion`` for a run folder (a humanoid-walk-open-loop run of the NAO, checked
    by its ``config.toml``), ``run`` for a ``.motion`` file."""
    run = Path(run)
    if run.is_dir():
        check_walk_run(run)
    path = run / "best.motion" if run.is_dir() else run
    if not path.is_file():
        raise InputError(f"{run}: expected a humanoid-walk-open-loop run folder (with "
                         "best.motion) or a .motion file")
    return path


def check_walk_run(run: Path, option: str = "RUN") -> None:
    """One line unless the folder ``run`` is a ``humanoid-walk-open-loop`` run of a foot-placement
    walk (the NAO's; its ``config.toml`` names the study and a robot with the capabilities of
    :data:`.gaits.FOOT_CAPABILITIES`; another study's run is refused, naming it)."""
    from evomotion.run.config import config_from_run_dir, configured_robot
    from evomotion.sim.robots import capabilities_of
    from evomotion.studies.humanoid_walk.gaits import FOOT_CAPABILITIES

    name, raw = config_from_run_dir(run)
    if name != "humanoid-walk-open-loop":
        raise InputError(f"{option} {run}: a {name} run, expected a humanoid-walk-open-loop "
                         "run folder (or a .motion file)")
    robot = configured_robot(raw)
    if not isinstance(robot, str) or not set(FOOT_CAPABILITIES) <= set(capabilities_of(robot)):
        raise InputError(f"{option} {run}: a walk of robot {str(robot)[:80]!r}; compare "
                         "replays NAO walks beside Webots' NAO motions")


def measure(motion: Motion, hold_s: float, trials: int = 0, seed: int = 0) -> dict:
    """Replay summary of one motion plus speed and heading per metre (and the fall rate in
    ``trials`` perturbed worlds)."""
    if trials:
        s = stress_motion(motion, StressOptions(trials=trials, seed=seed), hold_s=hold_s)
        s = s["summary"]
    else:
        s = simulate_motion(motion, hold_s=hold_s)["summary"]
    dx, dy = s["displacement_m"]
    dur = motion.duration_s
    row = {"duration_s": dur, "dx_m": dx, "dy_m": dy,
           "heading_deg": math.degrees(s["heading_change_rad"]),
           "speed_mps": dx / dur if dur > 0 else float("nan"),
           "heading_deg_per_m": (abs(math.degrees(s["heading_change_rad"])) / abs(dx)
                                 if abs(dx) >= MIN_DISTANCE_M else None),
           "fell": bool(s["fell"])}
    if trials:
        row["fall_rate"] = s["fall_rate"]
    return row


def compare(run: Path, hold_s: float = 1.0, trials: int = 0, seed: int = 0) -> dict[str, dict]:
    """``{motion name: row}``: the walk first, then Webots' motions."""
    path = walk_motion_path(run)
    rows = {f"evolved walk ({path.name})": measure(read_motion(path), hold_s, trials, seed)}
    for name in WEBOTS:
        rows[f"Webots {name}"] = measure(shipped_motion(name), hold_s, trials, seed)
    return rows


def table(rows: dict[str, dict]) -> str:
    """A Markdown table of :func:`compare`'s rows."""
    trials = any("fall_rate" in r for r in rows.values())
    head = "| motion | s | dx m | dy m | heading deg | m/s | deg/m | fell |" + \
        (" fall rate |" if trials else "")
    lines = [head, "|" + "---|" * (9 if trials else 8)]
    for name, r in rows.items():
        line = (f"| {name} | {r['duration_s']:.2f} | {r['dx_m']:+.3f} | {r['dy_m']:+.3f} | "
                f"{r['heading_deg']:+.1f} | {r['speed_mps']:+.3f} | "
                f"{_per_m(r['heading_deg_per_m'])} | {'yes' if r['fell'] else 'no'} |")
        if trials:
            line += f" {100 * r['fall_rate']:.0f}% |"
        lines.append(line)
    return "\n".join(lines)


def _per_m(v: float | None) -> str:
    return "—" if v is None else f"{v:.1f}"


def compare_command(run: Path, hold_s: float = 1.0, json_out: bool = False,
                    trials: int = 0, seed: int = 0) -> str:
    """CLI body: the table (or JSON) for stdout."""
    from evomotion.core.checks import check_number

    check_number("--hold", hold_s, lo=0.0, hi=60.0)
    check_number("--trials", trials, lo=0, hi=1000, integer=True)
    check_number("--seed", seed, lo=0, integer=True)
    rows = compare(run, hold_s, trials, seed)
    return json.dumps(rows, indent=2) if json_out else table(rows)
