"""Issue 12's and issue 31's hostile cases, run against this tree and, with ``--baseline REV``,
the package as committed at REV: each case's outcome as a before/after table.

Outcomes: ``one-line error`` (non-zero exit, one ``error:`` line, no traceback), ``ok`` (the
correct behaviour, checked), ``TRACEBACK``, ``SILENT`` (exit 0 but wrong), ``HANG`` (over the
time limit). Issue 31's cases (:mod:`hostile_cases_31`, run in the sandbox of
:mod:`hostile_harness`) add ``MEMORY`` (peak RSS above 1 GiB), ``TOUCHED`` (something outside
the paths the case may write changed, or /dev/null), ``KILLED`` (a process outside the run was
signalled), ``LATE`` (a refusal that came after the work) and ``FAILED`` (a command that should
have succeeded did not, or its result is wrong); a cell is the worst of them, with the longest
command's wall time and the peak RSS.

    python benchmarks/hostile_cases.py [--baseline aa2bf48] [--issue 12|31] [--only SUBSTRING]
                                       [--json DETAILS.json]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "tests" / "fixtures" / "webots-motions"


class Env:
    def __init__(self, src: Path | None, tmp: Path) -> None:
        self.env = dict(os.environ)
        if src is not None:
            self.env["PYTHONPATH"] = str(src)
        self.tmp = tmp

    def cli(self, *args: str, timeout: float = 300) -> subprocess.CompletedProcess:
        try:
            return subprocess.run([sys.executable, "-m", "evomotion.cli", *args], env=self.env,
                                  capture_output=True, text=True, timeout=timeout,
                                  cwd=self.tmp)
        except subprocess.TimeoutExpired:
            return subprocess.CompletedProcess(args, -999, "", "HANG")

    def py(self, code: str, *args: str, timeout: float = 300) -> subprocess.CompletedProcess:
        try:
            return subprocess.run([sys.executable, "-c", code, *args], env=self.env,
                                  capture_output=True, text=True, timeout=timeout,
                                  cwd=self.tmp)
        except subprocess.TimeoutExpired:
            return subprocess.CompletedProcess(args, -999, "", "HANG")


def verdict(r: subprocess.CompletedProcess, ok: bool | None = None) -> str:
    if r.returncode == -999:
        return "HANG"
    if "Traceback" in r.stderr:
        return "TRACEBACK"
    if r.returncode != 0:
        errs = [ln for ln in r.stderr.splitlines() if ln.startswith("error:")]
        return "one-line error" if len(errs) == 1 else f"exit {r.returncode}"
    if ok is None:
        return "SILENT"
    return "ok" if ok else "SILENT"


def _run(e: Env, name: str, *sets: str, study: str = "functions") -> Path:
    out = e.tmp / name
    args = ["run", study, "-q", "--out", str(out), "--set", "problem.dim=4",
            "--set", "algorithm.pop_size=20", "--set", "run.checkpoint_every=4"]
    for s in sets:
        args += ["--set", s]
    e.cli(*args)
    return out


def _latest(out: Path) -> tuple[Path, dict]:
    ck = out / "checkpoints"
    name = json.loads((ck / "latest.json").read_text())["checkpoint"]
    return ck / name, json.loads((ck / name).read_text())


def damaged(kind: str):
    def case(e: Env) -> str:
        out = _run(e, kind, "run.generations=10")
        r0 = e.cli("resume", str(out), "--set", "run.generations=20", "-q")
        if r0.returncode != 0:
            return "setup failed"
        out2 = _run(e, kind + "-2", "run.generations=10")
        path, meta = _latest(out2)
        ck = out2 / "checkpoints"
        if kind == "truncated latest.json":
            (ck / "latest.json").write_text('{"checkp')
        elif kind == "truncated checkpoint JSON":
            path.write_bytes(path.read_bytes()[:30])
        elif kind == "truncated npz":
            npz = ck / meta["arrays_file"]
            npz.write_bytes(npz.read_bytes()[:100])
        elif kind == "garbage npz":
            (ck / meta["arrays_file"]).write_bytes(os.urandom(2000))
        elif kind == "missing field":
            del meta["counters"]["evaluations"]
            path.write_text(json.dumps(meta))
        elif kind == "string for a number":
            meta["counters"]["generation"] = "ten"
            path.write_text(json.dumps(meta))
        elif kind == "population cut to 10 rows":
            import numpy as np

            npz = ck / meta["arrays_file"]
            with np.load(npz) as z:
                a = {k: z[k] for k in z.files}
            for k in a:
                if k.endswith(".pop") or k.endswith(".cost"):
                    a[k] = a[k][:10]
            np.savez(npz, **a)
        elif kind == "stats_offset past the end":
            meta["counters"]["stats_offset"] = 49_800_000
            path.write_text(json.dumps(meta))
        elif kind == "arrays_file outside the folder":
            other = _run(e, kind + "-other", "run.generations=10")
            meta["arrays_file"] = f"../../{other.name}/checkpoints/gen-000008.npz"
            path.write_text(json.dumps(meta))
        r = e.cli("resume", str(out2), "--set", "run.generations=20", "-q")
        stats = (out2 / "stats.csv").read_bytes()
        good = r.returncode == 0 and b"\0" not in stats and len(stats) < 100_000
        if good:
            ref = (out / "stats.csv").read_text().splitlines()
            got = stats.decode().splitlines()
            strip = [[c for i, c in enumerate(ln.split(",")) if i not in (9, 10)]
                     for ln in ref], [[c for i, c in enumerate(ln.split(",")) if i not in (9, 10)]
                                      for ln in got]
            good = strip[0] == strip[1]
        return verdict(r, good)
    return case


def concurrent(e: Env) -> str:
    out = e.tmp / "concurrent"
    args = ["run", "functions", "-q", "--out", str(out), "--set", "run.generations=3000",
            "--set", "problem.dim=4", "--set", "algorithm.pop_size=20"]
    p1 = subprocess.Popen([sys.executable, "-m", "evomotion.cli", *args], env=e.env,
                          cwd=e.tmp, stderr=subprocess.PIPE, text=True)
    time.sleep(2.0)
    r2 = e.cli(*args)
    p1.wait(timeout=300)
    rows = (out / "stats.csv").read_text().splitlines()
    intact = len(rows) == 3002 and [r.split(",")[0] for r in rows[1:]] == \
        [str(g) for g in range(3001)]
    v = verdict(r2)
    return f"second: {v}; first intact: {'yes' if intact else 'NO'}"


def second_run_old_folder(e: Env) -> str:
    out = _run(e, "old", "run.generations=10")
    before = (out / "stats.csv").read_text()
    r = e.cli("run", "functions", "-q", "--out", str(out), "--set", "problem.dim=4",
              "--set", "run.generations=5")
    same = (out / "stats.csv").read_text() == before
    return verdict(r, False) + ("" if same else "; old stats.csv changed")


def resume_seed(e: Env) -> str:
    out = _run(e, "seed", "run.generations=10", "run.seed=7")
    r = e.cli("resume", str(out), "--set", "run.seed=99", "--set", "run.generations=20", "-q")
    return verdict(r, False)


def bad_set(*items: str, study: str = "functions"):
    def case(e: Env) -> str:
        args = ["run", study, "-q", "--out", str(e.tmp / f"set{abs(hash(items))}")]
        for i in items:
            args += ["--set", i]
        args += ["--set", "run.generations=2"]
        return verdict(e.cli(*args, timeout=120), False)
    return case


def bad_file(kind: str, content: bytes | None, argv: list[str], ext: str):
    def case(e: Env) -> str:
        path = e.tmp / f"bad-{abs(hash(kind))}{ext}"
        if content is None:
            path.mkdir(exist_ok=True)
        else:
            path.write_bytes(content)
        args = [a.replace("FILE", str(path)) for a in argv]
        return verdict(e.cli(*args, timeout=120), False)
    return case


def bad_out(target: str):
    def case(e: Env) -> str:
        t = target
        if t == "EXISTING_FILE":
            t = str(e.tmp / "a-file")
            Path(t).write_text("x")
        return verdict(e.cli("run", "functions", "-q", "--out", t, "--set",
                             "run.generations=1"), False)
    return case


def all_nan(e: Env) -> str:
    """Every fitness NaN (the test-only toy study of tests/run, NaN above x0 = -10)."""
    out = e.tmp / "nan"
    code = ("import sys, json\n"
            f"sys.path.insert(0, {str(ROOT / 'tests' / 'run')!r})\n"
            "from toy_study import STUDY\n"
            "from evomotion.run.config import resolve_config\n"
            "from evomotion.run.runner import run_study\n"
            "cfg = resolve_config(STUDY, None, ['run.generations=2', 'problem.nan_above=-10',"
            " 'problem.raise_above=9'])\n"
            "res = run_study(STUDY, cfg, sys.argv[1], quiet=True)\n"
            "sys.exit(res.exit_code)\n")
    r = e.py(code, str(out))
    try:
        json.loads((out / "best.json").read_text())
        valid = True
    except (OSError, ValueError):
        valid = False
    ok = r.returncode != 0 and valid and "Traceback" not in r.stderr
    if r.returncode == 0:
        return "exit 0" + ("" if valid else "; best.json not JSON")
    return ("non-zero exit, valid JSON" if ok else verdict(r)) + ("" if valid else
                                                                 "; best.json not JSON")


def parent_kill(e: Env) -> str:
    code = ("import sys, time, numpy as np\n"
            "from evomotion.run.evaluators import ProcessEvaluator\n"
            "from evomotion.studies import get_study\n"
            "s = get_study('functions')\n"
            "ev = ProcessEvaluator(s.make_problem, s.problem_config(dim=4), workers=2)\n"
            "ev(np.zeros((4, 4)))\n"
            "print('ready', flush=True)\n"
            "time.sleep(300)\n")
    p = subprocess.Popen([sys.executable, "-c", code], env=e.env, stdout=subprocess.PIPE,
                         text=True, cwd=e.tmp)
    p.stdout.readline()
    kids = subprocess.run(["pgrep", "-P", str(p.pid)], capture_output=True,
                          text=True).stdout.split()
    os.kill(p.pid, signal.SIGKILL)
    p.wait()
    time.sleep(3)
    alive = [k for k in kids if Path(f"/proc/{k}").exists()
             and "Z" not in Path(f"/proc/{k}/stat").read_text().split()[2]]
    for k in alive:
        os.kill(int(k), signal.SIGKILL)
    return "ok" if kids and not alive else f"{len(alive)} worker(s) alive after 3 s"


def big_map(e: Env) -> str:
    import numpy as np

    n = 7100
    rows = np.where(np.random.default_rng(0).random((n, n)) < 0.2, "@", ".")
    path = e.tmp / "big.map"
    with open(path, "w") as fh:
        fh.write(f"type octile\nheight {n}\nwidth {n}\nmap\n")
        fh.write("\n".join("".join(r) for r in rows) + "\n")
    code = ("import sys, time\nt = time.perf_counter()\n"
            "from evomotion.studies.grid_path.maps import read_map\n"
            "read_map(sys.argv[1])\nprint(f'{time.perf_counter() - t:.1f}')\n")
    r = e.py(code, str(path), timeout=400)
    if r.returncode == -999:
        return "read > 400 s"
    return f"read {r.stdout.strip()} s" if r.returncode == 0 else verdict(r)


def cases() -> dict:
    motion = (FIXTURES / "HandWave.motion").read_text() if FIXTURES.exists() else ""
    lines = motion.splitlines()

    def motion_with(value: str, time_stamp: str | None = None) -> bytes:
        out = list(lines)
        poses = [k for k, ln in enumerate(out) if ln[:1].isdigit()]
        i = poses[-1] if time_stamp is not None else poses[0]  # a late stamp on the last pose
        cols = out[i].split(",")
        cols[2] = value
        if time_stamp is not None:
            cols[0] = time_stamp
        out[i] = ",".join(cols)
        return ("\n".join(out) + "\n").encode()

    plan_ok = {"goal": "abc"}
    return {
        "two concurrent runs, same --out": concurrent,
        "second run into an old run folder": second_run_old_folder,
        **{f"resume: {k}": damaged(k) for k in (
            "truncated latest.json", "truncated checkpoint JSON", "truncated npz",
            "garbage npz", "missing field", "string for a number",
            "population cut to 10 rows", "stats_offset past the end",
            "arrays_file outside the folder")},
        "resume --set run.seed=99": resume_seed,
        "kill -9 of the parent: process workers": parent_kill,
        "non-UTF-8 TOML config": bad_file("toml", b"[run]\nseed = 1\n# \xff\xfe\n",
                                          ["run", "functions", "--config", "FILE", "-q"],
                                          ".toml"),
        "non-UTF-8 .map": bad_file("map", b"type octile\nheight 2\nwidth 2\nmap\n.\xff\n..\n",
                                   ["run", "grid-path", "-q", "--set", "problem.map='FILE'"],
                                   ".map"),
        "height 0 in a .map": bad_file("map0", b"type octile\nheight 0\nwidth 2\nmap\n",
                                       ["run", "grid-path", "-q", "--set",
                                        "problem.map='FILE'"], ".map"),
        "non-UTF-8 plan.json": bad_file("plan", b'{"goal": "\xff"}',
                                        ["quadruped-plan", "check", "FILE"], ".json"),
        "plan.json goal \"abc\"": bad_file("plan2", json.dumps(plan_ok).encode(),
                                           ["quadruped-plan", "check", "FILE"], ".json"),
        "plan.json is a directory": bad_file("plan3", None,
                                             ["quadruped-plan", "check", "FILE"], ".json"),
        "nan in a .motion": bad_file("mnan", motion_with("nan"), ["replay", "FILE", "--json"],
                                     ".motion"),
        "inf in a .motion": bad_file("minf", motion_with("inf"), ["replay", "FILE", "--json"],
                                     ".motion"),
        "time stamp 99999999999 in a .motion": bad_file(
            "mtime", motion_with("0.1", "99999999999"), ["replay", "FILE", "--json"], ".motion"),
        "problem.half_width=nan": bad_set("problem.half_width=nan"),
        "problem.half_width=inf": bad_set("problem.half_width=inf"),
        "problem.dim=1e9": bad_set("problem.dim=1000000000"),
        "algorithm.pop_size=1e9": bad_set("algorithm.pop_size=1000000000"),
        "mutation_params={bogus=1}": bad_set("algorithm.mutation_params={bogus=1}"),
        "mutation_params={sigma=nan}": bad_set("algorithm.mutation_params={sigma=nan}"),
        "run.wall_seconds=nan": bad_set("run.wall_seconds=nan"),
        "quadruped algorithm.max_seconds=nan": bad_set("algorithm.max_seconds=nan",
                                                       study="quadruped-plan"),
        "--out /proc/x": bad_out("/proc/x"),
        "--out EXISTING_FILE": bad_out("EXISTING_FILE"),
        "--out /dev/null/x": bad_out("/dev/null/x"),
        "every fitness NaN": all_nan,
        "7,100 x 7,100 map (50 MB)": big_map,
    }


def _run_31(name: str, case, trees: dict, tmp: Path) -> tuple[list[str], list[dict]]:
    from hostile_harness import (
        Box,
        SetupError,
        devnull_ok,
        restore_devnull,
        worst,
    )

    cells, details = [], []
    for label, src in trees.items():
        work = Path(tempfile.mkdtemp(dir=tmp)) / "case"
        work.mkdir()
        box = Box(src, work, label, tmp / "cache" / label.replace(" ", "-"))
        try:
            v = case(box)
        except SetupError as e:
            v = f"setup failed ({e})"
        except Exception as e:  # noqa: BLE001 - a broken case is reported, not fatal
            v = f"case failed ({type(e).__name__}: {e})"[:90]
        flags = []
        try:
            touched = box.touched()
        finally:
            box.close()
        if touched:
            flags.append(f"TOUCHED ({', '.join(touched)[:40]})")
        if not devnull_ok():
            restore_devnull()
            flags.append("TOUCHED (/dev/null replaced; restored)")
        if any(r.hang for r in box.results) and not v.startswith("HANG"):
            flags.append("HANG")
        if any(r.memory for r in box.results):
            flags.append(f"MEMORY ({max(r.maxrss_kb for r in box.results) >> 10} MB)")
        verdict = worst([v, *flags])
        wall = max((r.wall for r in box.results), default=0.0)
        rss = max((r.maxrss_kb for r in box.results), default=0) >> 10
        cells.append(f"{verdict} · {wall:.1f} s · {rss} MB")
        last = box.results[-1] if box.results else None
        details.append({"case": name, "tree": label, "verdict": verdict, "case_verdict": v,
                        "flags": flags, "wall_s": round(wall, 2), "peak_mb": rss,
                        "argv": [str(a) for a in last.args][-12:] if last else None,
                        "rc": last.returncode if last else None,
                        "stderr": last.stderr[-1500:] if last else None,
                        "stdout": last.stdout[-600:] if last else None})
        shutil.rmtree(work.parent, ignore_errors=True)
    return cells, details


def _summary(rows: list[list[str]], labels: list[str]) -> str:
    from hostile_harness import is_good

    parts = []
    for i, label in enumerate(labels):
        verdicts = [r[i].split(" · ")[0] for r in rows]
        good = sum(is_good(v) for v in verdicts)
        kinds: dict[str, int] = {}
        for v in verdicts:
            if not is_good(v):
                k = v.split(" (")[0].split(" ")[0]
                kinds[k] = kinds.get(k, 0) + 1
        bad = ", ".join(f"{n} {k}" for k, n in sorted(kinds.items(), key=lambda x: -x[1]))
        parts.append(f"{label}: {good} of {len(rows)} ok or one-line error"
                     + (f" ({bad})" if bad else ""))
    return "; ".join(parts)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--baseline", default=None)
    ap.add_argument("--only", default=None)
    ap.add_argument("--issue", choices=("12", "31"), default=None,
                    help="only this issue's cases (default: both)")
    ap.add_argument("--json", default=None, help="write every cell's details here")
    a = ap.parse_args()
    trees: dict[str, Path | None] = {"this tree": None}
    details: list[dict] = []
    with tempfile.TemporaryDirectory() as tmp:
        if a.baseline:
            tar = subprocess.run(["git", "-C", str(ROOT), "archive", a.baseline, "src"],
                                 check=True, capture_output=True).stdout
            (Path(tmp) / "base").mkdir()
            subprocess.run(["tar", "-x", "-C", str(Path(tmp) / "base")], input=tar, check=True)
            trees = {a.baseline: Path(tmp) / "base" / "src", "this tree": None}
        header = "| case | " + " | ".join(trees) + " |\n|---|" + "---|" * len(trees)
        if a.issue in (None, "12"):
            print("### issue 12\n\n" + header)
            for name, case in cases().items():
                if a.only and a.only not in name:
                    continue
                cells = []
                for label, src in trees.items():
                    work = Path(tempfile.mkdtemp(dir=tmp))
                    try:
                        cells.append(case(Env(src, work)))
                    except Exception as e:  # noqa: BLE001 - a broken case is reported
                        cells.append(f"case failed: {type(e).__name__}: {e}"[:80])
                    shutil.rmtree(work, ignore_errors=True)
                print(f"| {name} | " + " | ".join(cells) + " |", flush=True)
        if a.issue in (None, "31"):
            from hostile_cases_31 import cases as cases_31

            print("\n### issue 31\n\n" + header, flush=True)
            rows = []
            for name, case in cases_31().items():
                if a.only and a.only not in name:
                    continue
                cells, d = _run_31(name, case, trees, Path(tmp))
                rows.append(cells)
                details += d
                print(f"| {name} | " + " | ".join(cells) + " |", flush=True)
            print(f"\n{len(rows)} cases; " + _summary(rows, list(trees)), flush=True)
    if a.json:
        Path(a.json).write_text(json.dumps(details, indent=1))


if __name__ == "__main__":
    main()
