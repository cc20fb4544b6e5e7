"""The "same guarantees for every study" table of issue 11, measured on the installed package.

For each study (small settings so that the table takes a few minutes on 2 cores):

- resume: a run SIGINTed (Ctrl-C) and one SIGKILLed (kill -9) during step 4, then
  ``evomotion resume``, against an uninterrupted run: "yes, bit-identical" when stats.csv
  (minus timing columns) and best.json agree;
- evaluator: ``--evaluator process --workers 2`` against serial (or the one-line refusal of a
  study without batch evaluation);
- stop rules: which of ``run.generations``, ``run.max_evaluations``, ``run.wall_seconds``,
  ``run.target`` and stagnation end a run with their own stop reason;
- stats.csv: the core columns first, and the count of study columns after them;
- ``evomotion plot RUN``: exit code;
- console: on a terminal (``script``) a Rich progress bar; otherwise the final line only.

    python benchmarks/run_loop_table.py [--study arm-ik ...]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

TARGET = {"functions": "1e9", "humanoid-step": "0.0", "biped-kick": "-100.0", "arm-ik": "1e9",
          "grid-path": "1e9", "quadruped-plan": "1e9"}
KILL = """
import sys
from evomotion.run.config import resolve_config
from evomotion.run.faults import fault_at
from evomotion.run.runner import run_study
from evomotion.studies import get_study
name, out, cut, how = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
s = get_study(name)
with fault_at(cut, how):
    res = run_study(s, resolve_config(s, None, sys.argv[5:]), out, quiet=True)
sys.exit(res.exit_code)
"""
TIMED = {"wall_s", "evals_per_s"}


def cli(*args: str, tty: bool = False) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "evomotion.cli", *args]
    if tty and shutil.which("script"):
        cmd = ["script", "-qec", " ".join(cmd), "/dev/null"]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=900,
                          env=dict(os.environ, COLUMNS="100"))


def sets(name: str, extra: list[str]) -> list[str]:
    out = []
    from evomotion.studies import get_study

    for s in [*get_study(name).smoke, "run.checkpoint_every=2", "run.seed=5", *extra]:
        out += ["--set", s]
    return out


def same(a: Path, b: Path) -> bool:
    import csv

    rows = [list(csv.DictReader((d / "stats.csv").read_text().splitlines())) for d in (a, b)]
    strip = [[{k: v for k, v in r.items() if k not in TIMED} for r in rs] for rs in rows]
    ba, bb = (json.loads((d / "best.json").read_text()) for d in (a, b))
    keys = [k for k in ba if k != "time_to_solution_s"]
    return strip[0] == strip[1] and all(ba[k] == bb.get(k) for k in keys)


def resume_cell(name: str, tmp: Path, gens: int) -> str:
    full = tmp / "full"
    cli("run", name, "-q", "--out", str(full), *sets(name, [f"run.generations={gens}"]))
    out = []
    for sig, label in (("sigint", "Ctrl-C"), ("sigkill", "kill -9")):
        d = tmp / f"cut-{sig}"
        d.mkdir()
        args = [a for a in sets(name, [f"run.generations={gens}"]) if a != "--set"]
        subprocess.run([sys.executable, "-c", KILL, name, str(d), "3", sig, *args],
                       capture_output=True, text=True, timeout=900)
        r = cli("resume", str(d), "-q")
        ok = "Traceback" not in r.stderr and same(full, d)
        out.append(f"{label}: {'yes' if ok else 'NO'}")
    return ", ".join(out) + (" (bit-identical)" if all("yes" in o for o in out) else "")


def evaluator_cell(name: str, tmp: Path) -> str:
    r = cli("run", name, "-q", "--out", str(tmp / "proc"), "--evaluator", "process",
            "--workers", "2", *sets(name, ["run.generations=4"]))
    if r.returncode == 2:
        return "refused: " + r.stderr.strip().splitlines()[-1][:60]
    cli("run", name, "-q", "--out", str(tmp / "ser"), *sets(name, ["run.generations=4"]))
    return "process = serial" if same(tmp / "ser", tmp / "proc") else "process DIFFERS"


def stop_cell(name: str, tmp: Path) -> str:
    rules = {"generations": ["run.generations=3"],
             "max_evaluations": ["run.generations=1000", "run.max_evaluations=1"],
             "wall_seconds": ["run.generations=100000", "run.wall_seconds=0.01"],
             "target": ["run.generations=1000", f"run.target={TARGET[name]}"],
             "stagnation": ["run.generations=100000", "run.stagnation_generations=1",
                            "run.stagnation_eps=1e300"]}
    ok = []
    for rule, extra in rules.items():
        d = tmp / f"stop-{rule}"
        cli("run", name, "-q", "--out", str(d), *sets(name, extra))
        best = json.loads((d / "best.json").read_text()) if (d / "best.json").exists() else {}
        own = best.get("stop_reason")
        ok.append(rule if own == rule else f"{rule}->{own}")
    return f"{sum('->' not in o for o in ok)}/5" + (
        "" if all("->" not in o for o in ok) else " (" + ", ".join(
            o for o in ok if "->" in o) + ")")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--study", action="append", default=None)
    a = ap.parse_args()
    from evomotion.run.stats import COLUMNS
    from evomotion.studies import STUDIES

    names = a.study or list(STUDIES)
    print("| | " + " | ".join(names) + " |\n|---|" + "---|" * len(names))
    cells: dict[str, list[str]] = {k: [] for k in (
        "resume after Ctrl-C / kill -9", "`--evaluator`", "stop rules", "stats.csv",
        "`evomotion plot RUN`", "console")}
    for name in names:
        with tempfile.TemporaryDirectory() as t:
            tmp = Path(t)
            cells["resume after Ctrl-C / kill -9"].append(resume_cell(name, tmp, 6))
            cells["`--evaluator`"].append(evaluator_cell(name, tmp))
            cells["stop rules"].append(stop_cell(name, tmp))
            head = (tmp / "full" / "stats.csv").read_text().splitlines()[0].split(",")
            core = tuple(head[:len(COLUMNS)]) == COLUMNS
            first = "first" if core else "MISSING"
            cells["stats.csv"].append(f"{len(COLUMNS)} core columns {first}"
                                      f" + {len(head) - len(COLUMNS)} study")
            r = cli("plot", str(tmp / "full"))
            cells["`evomotion plot RUN`"].append("works" if r.returncode == 0 else
                                                 f"exit {r.returncode}")
            r = cli("run", name, "--out", str(tmp / "tty"), *sets(name, ["run.generations=3"]),
                    tty=True)
            bar = "━" in r.stdout or "gen " in r.stdout
            cells["console"].append("Rich bar" if bar else "no bar")
    for k, v in cells.items():
        print(f"| {k} | " + " | ".join(v) + " |")


if __name__ == "__main__":
    main()
