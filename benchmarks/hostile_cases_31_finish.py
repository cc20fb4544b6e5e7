"""Issue 31, class 4: a run killed (SIGKILL, from outside) while it writes its final
artifacts; ``evomotion resume`` must complete them, equal to an uninterrupted run's.

Per study (its smoke settings, 4 generations, no videos; and the quadruped's receding method):
an uninterrupted run measures the finishing phase (from the log's ``stopped:`` line to the
exit); a second run of the same seed is killed half-way through it; ``resume`` must exit as
the uninterrupted run did, and every file must equal the uninterrupted run's, except log.txt,
run.lock, checkpoints/ and the timing fields (stats.csv columns wall_s, evals_per_s, plan_ms*;
JSON keys wall_s, evals_per_s, expansions_per_s, time_to_solution_s, elapsed_s, seconds,
plan_ms*).
"""

from __future__ import annotations

import json
import os
import signal
import sys
from pathlib import Path

from hostile_cases_31 import QUAD_SMOKE, TINY_WORLD, q, sets
from hostile_harness import Box, expect_ok, run_command

SMOKE = {
    "functions": ["problem.dim=4", "algorithm.pop_size=10"],
    "grid-path": ["algorithm.pop_size=16"],
    "arm-ik": ["algorithm.pop_size=8", "algorithm.arm_generations=2",
               "algorithm.finger_generations=2", "problem.pictures=false",
               "problem.scenario='three_fingers'"],
    "biped-kick": ["algorithm.pop_size=4", "run.max_evaluations=0"],
    "humanoid-step": ["algorithm.pop_size=6", "problem.motion_s=0.4", "problem.hold_s=0.2",
                      "problem.intervals=4"],
    "humanoid-walk-open-loop": ["algorithm.pop_size=4", "problem.walk_s=0.5", "problem.hold_s=0.2",
                      "problem.worlds=2"],
    "humanoid-repertoire": ["algorithm.emitters=2", "algorithm.pop_size=4", "problem.hold_s=0.2"],
    "quadruped-plan": QUAD_SMOKE,
}
COMMON = ["run.generations=4", "run.checkpoint_every=2", "run.wall_seconds=0", "run.seed=5",
          "run.videos=false"]
SKIP = {"log.txt", "run.lock", "checkpoints"}
TIMED_KEYS = {"wall_s", "evals_per_s", "expansions_per_s", "time_to_solution_s", "elapsed_s",
              "seconds"}


def _timed(key: str) -> bool:
    return key in TIMED_KEYS or key.startswith("plan_ms")


def watched_run(b: Box, args: list[str], out: str, kill_after: float | None,
                limit: float = 300) -> tuple[int, float | None, float]:
    """Run ``args --out out``; ``(exit status, seconds from start to the log's 'stopped:'
    line, seconds to the exit)``; ``kill_after``: SIGKILL that long after 'stopped:'."""
    log = b.tmp / out / "log.txt"
    seen: dict = {"stop": None}

    def tick(now: float) -> bool:
        if seen["stop"] is None:
            try:
                if b"\nstopped: " in log.read_bytes():
                    seen["stop"] = now
            except OSError:
                pass
            return False
        return kill_after is not None and now >= seen["stop"] + kill_after

    r = run_command([sys.executable, "-m", "evomotion.cli", *args, "--out", out], b.tmp, b.env,
                    limit, b.tmp.parent / f"{b.tmp.name}.logs" / f"watch-{out}", on_tick=tick)
    b.results.append(r)
    return r.returncode, seen["stop"], r.wall


def _normal(path: Path, rel: str) -> bytes | object:
    data = path.read_bytes()
    if rel.endswith("stats.csv"):
        rows = [ln.split(",") for ln in data.decode("utf-8", "replace").splitlines()]
        keep = [i for i, c in enumerate(rows[0] if rows else []) if not _timed(c)]
        return [[r[i] for i in keep if i < len(r)] for r in rows]
    if rel.endswith(".json"):
        def strip(o):
            if isinstance(o, dict):
                return {k: strip(v) for k, v in o.items() if not _timed(k)}
            if isinstance(o, list):
                return [strip(v) for v in o]
            return o
        try:
            return strip(json.loads(data))
        except ValueError:
            return data
    return data


def compare(ref: Path, got: Path) -> list[str]:
    """The files that differ between two run folders (``-name``: missing, ``+name``: extra)."""
    def files(root: Path) -> set[str]:
        out = set()
        for dirpath, dirnames, names in os.walk(root):
            rel = os.path.relpath(dirpath, root)
            if rel == ".":
                dirnames[:] = [d for d in dirnames if d not in SKIP]
            out |= {os.path.normpath(os.path.join(rel, n)) for n in names
                    if rel != "." or n not in SKIP}
        return out
    a, b_ = files(ref), files(got)
    diff = [f"-{n}" for n in sorted(a - b_)] + [f"+{n}" for n in sorted(b_ - a)]
    diff += [n for n in sorted(a & b_) if _normal(ref / n, n) != _normal(got / n, n)]
    return diff


def finish_case(study: str, method: str | None = None):
    def case(b: Box) -> str:
        extra = SMOKE.get(study, [])
        if method == "receding":
            (b.tmp / "tiny.world").write_text(TINY_WORLD)
            extra = ["algorithm.name=receding", f"problem.world={q(b.tmp / 'tiny.world')}",
                     "problem.gif_max_frames=4"]
        args = ["run", study, "-q", *sets(*extra, *COMMON)]
        b.allow = ["ref", "run"]
        b.arm()
        rc_ref, t_stop, t_end = watched_run(b, args, "ref", None)
        if t_stop is None:
            return f"setup failed (no 'stopped:' line; exit {rc_ref})"
        finishing = t_end - t_stop
        rc_k, t_stop_k, _ = watched_run(b, args, "run", 0.5 * finishing)
        if rc_k != -signal.SIGKILL:
            return f"n/a (the run ended before the kill: exit {rc_k})"
        r = b.cli("resume", "run", "-q", limit=10 + 2 * finishing)
        if r.returncode != rc_ref and not r.hang and "Traceback" not in r.stderr:
            errs = r.error_lines()
            return f"FAILED ({(errs[-1][7:] if errs else f'exit {r.returncode}')[:48]})"
        diff = compare(b.tmp / "ref", b.tmp / "run")
        r.returncode = 0 if r.returncode == rc_ref else r.returncode
        return expect_ok(r, not diff, "differ: " + ", ".join(diff)[:60]).replace(
            "SILENT (differ", "FAILED (differ")
    return case


def cases() -> dict:
    out = {}
    for study in sorted(SMOKE):
        out[f"F kill -9 while finishing, resume: {study}"] = finish_case(study)
    out["F kill -9 while finishing, resume: quadruped-plan receding"] = \
        finish_case("quadruped-plan", "receding")
    return out
