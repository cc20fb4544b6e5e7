"""Issue 31's hostile cases ("nothing lost, nothing killed, nothing crashes"), by class of
fault: ownership of folders (here), process safety and the studio
(:mod:`hostile_cases_31_procs`), writes (:mod:`hostile_cases_31_files`), readers
(:mod:`hostile_cases_31_readers`), the finishing phase (:mod:`hostile_cases_31_finish`) and
inputs that used to be accepted (here). Each case is ``case(box) -> verdict``; the sandbox
(:mod:`hostile_harness`) adds HANG, MEMORY and TOUCHED. Run by ``hostile_cases.py --issue 31``.

Fixtures (a finished run of a study, built once per tree and copied into each case folder)
come from :func:`fixture`; the case folder's bystander tree is ``project/`` and ``outside/``.
"""

from __future__ import annotations

import json
import os
import random
import shutil
import sys
from importlib import resources
from pathlib import Path

from hostile_harness import Box, Result, SetupError, expect_error, expect_ok, q, run_command

MOTIONS = Path(str(resources.files("evomotion.sim.robots.nao") / "motions"))
FN = ["--set", "problem.dim=4", "--set", "algorithm.pop_size=10", "--set", "run.generations=3"]
TINY_WORLD = """# a small world: a rock to walk round, a puddle, a hidden post
name tiny
bounds -6 -8 16 9
start 0 0 90
goal 10 0 0.25
view 8
obstacle 4 -1  5.5 -1  5.5 0.8  4 0.8
nostep 1 3.5  3 3.5  3 5  1 5
hidden 8.5 -4  9.5 -4  9.5 -3  8.5 -3
"""
QUAD_SMOKE = ["algorithm.batch_expansions=40", "problem.goal_x=0.0", "problem.goal_y=-7.0",
              "problem.start_phi=0.0", "problem.gif_max_frames=4"]


def sets(*items: str) -> list[str]:
    out = []
    for s in items:
        out += ["--set", s]
    return out


def _fixture_args(name: str, cache: Path) -> tuple[list[str], tuple[int, ...]]:
    off = ["run.videos=false", "run.wall_seconds=0"]
    if name == "fn":
        return ["run", "functions", "-q", *sets("problem.dim=4", "algorithm.pop_size=10",
                                                "run.generations=10", "run.checkpoint_every=4",
                                                "run.history_every=1")], (0,)
    if name == "rep":
        return ["run", "humanoid-repertoire", "-q", *sets(
            "algorithm.emitters=2", "algorithm.pop_size=4", "problem.hold_s=0.2",
            "run.generations=3", *off)], (0,)
    if name == "plan":
        return ["run", "quadruped-plan", "-q", *sets(*QUAD_SMOKE, "run.generations=400",
                                                     *off)], (0,)
    if name == "mission":
        (cache / "tiny.world").write_text(TINY_WORLD)
        return ["run", "quadruped-plan", "-q", *sets(
            "algorithm.name=receding", f"problem.world={q(cache / 'tiny.world')}",
            "problem.gif_max_frames=4", "run.generations=4", *off)], (0, 1)
    if name == "kick":
        return ["run", "biped-kick", "-q", *sets("algorithm.pop_size=4",
                                                 "run.max_evaluations=0", "run.generations=1",
                                                 *off)], (0,)
    raise KeyError(name)


def fixture(b: Box, name: str, dest: str | None = None) -> Path:
    """A copy of the finished run ``name`` (built once per tree) at ``box/dest``."""
    cache = b.cache
    cache.mkdir(parents=True, exist_ok=True)
    built, failed = cache / name, cache / f"{name}.failed"
    if failed.exists():
        raise SetupError(failed.read_text())
    if not built.exists():
        args, ok = _fixture_args(name, cache)
        r = run_command([sys.executable, "-m", "evomotion.cli", *args, "--out",
                         str(cache / f"{name}.tmp")], cache, b.env, 600, cache / "logs" / name)
        if r.returncode not in ok:
            tail = (r.stderr.strip().splitlines() or [f"exit {r.returncode}"])[-1]
            failed.write_text(f"fixture {name}: {tail}"[:70])
            raise SetupError(failed.read_text())
        (cache / f"{name}.tmp").rename(built)
    out = b.tmp / (dest or name)
    shutil.copytree(built, out, symlinks=True)
    return out


def short_motion(b: Box, name: str = "short.motion") -> Path:
    """A three-pose, 0.2 s .motion of the NAO's legs (cheap to replay and render)."""
    lines = (MOTIONS / "TurnRight40.motion").read_text().splitlines()
    poses = [ln for ln in lines if ln[:1].isdigit()][:3]
    out = [ln for ln in lines if not ln[:1].isdigit()]
    for i, ln in enumerate(poses):
        cols = ln.split(",")
        cols[0] = f"00:00:{100 * i:03d}"
        cols[1] = f"Pose{i + 1}"
        out.append(",".join(cols))
    p = b.tmp / name
    p.write_text("\n".join(out) + "\n")
    return p


def names_in(r: Result, *names: str) -> bool:
    errs = " ".join(r.error_lines())
    return all(n in errs for n in names)


# --- class 1: ownership ------------------------------------------------------------------

def overwrite_project(b: Box) -> str:
    return expect_error(b.cli("run", "functions", "-q", "--out", "project", "--overwrite", *FN))


def overwrite_project_path_trick(b: Box) -> str:
    return expect_error(b.cli("run", "functions", "-q", "--out", "project/src/..",
                              "--overwrite", *FN))


def overwrite_link_to_project(b: Box) -> str:
    os.symlink("project", b.tmp / "link")
    return expect_error(b.cli("run", "functions", "-q", "--out", "link", "--overwrite", *FN))


def overwrite_user_file(b: Box) -> str:
    run = fixture(b, "fn", "run")
    (run / "notes.txt").write_text("my notes\n")
    r = b.cli("run", "functions", "-q", "--out", "run", "--overwrite", *FN)
    v = expect_error(r)
    return v if v != "one-line error" or names_in(r, "notes.txt") else \
        "FAILED (the error does not name notes.txt)"


def overwrite_unmarked(b: Box) -> str:
    run = fixture(b, "fn", "run")
    (run / ".evomotion-run").unlink(missing_ok=True)  # a run written before the marker
    return expect_error(b.cli("run", "functions", "-q", "--out", "run", "--overwrite", *FN))


def overwrite_claimed_link(target: str, name: str):
    def case(b: Box) -> str:
        run = fixture(b, "fn", "run")
        p = run / name
        shutil.rmtree(p) if p.is_dir() and not p.is_symlink() else p.unlink(missing_ok=True)
        os.symlink(b.tmp / target, p)
        b.allow = ["run"]
        r = b.cli("run", "functions", "-q", "--out", "run", "--overwrite", *FN)
        if r.returncode != 0:
            return expect_error(r)
        return expect_ok(r, (run / "best.json").is_file() and not (run / "best.json").is_symlink(),
                         "best.json missing")
    return case


def overwrite_forged_marker(b: Box) -> str:
    run = fixture(b, "fn", "run")
    doc = {"evomotion_run": 1, "study": "functions",
           "files": ["..", "../outside", "../project", str(b.tmp / "outside"), "/", "config.toml",
                     "stats.csv", "log.txt", "checkpoints", "best.json", "plots"]}
    (run / ".evomotion-run").write_text(json.dumps(doc))
    b.allow = ["run"]
    r = b.cli("run", "functions", "-q", "--out", "run", "--overwrite", *FN)
    return expect_error(r) if r.returncode != 0 else \
        expect_ok(r, (run / "best.json").is_file(), "best.json missing")


def overwrite_own_run(b: Box) -> str:
    """The control: --overwrite of a run folder holding only what the run wrote."""
    run = fixture(b, "fn", "run")
    b.allow = ["run"]
    r = b.cli("run", "functions", "-q", "--out", "run", "--overwrite", *FN)
    ok = (run / "stats.csv").is_file() and \
        len((run / "stats.csv").read_text().splitlines()) == 5
    return expect_ok(r, ok, "stats.csv not the new run's")


def new_run_into(target: str):
    def case(b: Box) -> str:
        t = target
        if target == "fifo":
            os.mkfifo(b.tmp / "fifo")
        elif target == "socket":
            import socket

            s = socket.socket(socket.AF_UNIX)
            s.bind(str(b.tmp / "socket"))
            s.close()
        ns = "dev" if t.startswith("/dev") else None
        return _devcheck(b, b.cli("run", "functions", "-q", "--out", t, *FN, ns=ns))
    return case


def _devcheck(b: Box, r: Result) -> str:
    from hostile_cases_31_files import _devnull

    return _devnull(r) or expect_error(r)


# --- class 6: accepted when it should be refused ------------------------------------------

def kick_plan(*args: str):
    def case(b: Box) -> str:
        b.allow = ["kick-plan.png", "k.png"]
        return expect_error(b.cli("biped-kick", "plan", *args, "--out", "k.png"))
    return case


def repertoire_hold(value: str):
    def case(b: Box) -> str:
        run = fixture(b, "rep")
        b.allow = ["rep"]
        r = b.cli("humanoid-repertoire", "export", "rep", "--hold", value)
        if r.returncode == 0:
            text = (run / "repertoire" / "index.json").read_text()
            bad = any(w in text for w in ("NaN", "Infinity", '"hold_s": -'))
            return "SILENT (index.json holds " + value + ")" if bad else "SILENT"
        return expect_error(r)
    return case


def walk_compare_kick(b: Box) -> str:
    fixture(b, "kick")
    return expect_error(b.cli("humanoid-walk-open-loop", "compare", "kick", "--json"))


def spec_copy(b: Box, edit: dict | None = None, name: str = "robot") -> Path:
    """A copy of the bundled OP3 spec and MJCF in ``box/robot/`` (``edit``: text
    replacements in the spec)."""
    specs = Path(str(resources.files("evomotion.sim.robots") / "op3"))
    model = specs / "op3.xml"
    d = b.tmp / name
    d.mkdir(exist_ok=True)
    shutil.copy(model, d / "op3.xml")
    text = (specs / "op3.toml").read_text().replace('"evomotion:sim/robots/op3/op3.xml"',
                                                      '"op3.xml"')
    for old, new in (edit or {}).items():
        if old not in text:
            raise SetupError(f"spec edit: {old!r} not in op3.toml")
        text = text.replace(old, new)
    (d / "op3.toml").write_text(text)
    return d / "op3.toml"


STEP_SMOKE = sets("algorithm.pop_size=6", "problem.motion_s=0.4", "problem.hold_s=0.2",
                  "problem.intervals=4", "run.generations=1", "run.videos=false")


def robot_run(b: Box, spec: Path, limit: float = 10.0) -> Result:
    b.allow = ["out"]
    return b.cli("run", "humanoid-step", "-q", "--out", "out", "--robot", str(spec),
                 *STEP_SMOKE, limit=limit)


def spec_value(edit: dict):
    def case(b: Box) -> str:
        r = robot_run(b, spec_copy(b, edit))
        if r.returncode == 0 and "Nan, Inf or huge value" in r.stderr:
            return "SILENT (MuJoCo instability warnings)"
        return expect_error(r)
    return case


def goal_in_obstacle(b: Box) -> str:
    world = TINY_WORLD.replace("goal 10 0 0.25", "goal 4.7 -0.1 0.25")
    (b.tmp / "goal.world").write_text(world)
    b.allow = ["out"]
    return expect_error(b.cli("run", "quadruped-plan", "-q", "--out", "out", *sets(
        f"problem.world={q(b.tmp / 'goal.world')}", "run.videos=false")), quick_s=8)


def plot_damaged(kind: str):
    def case(b: Box) -> str:
        run = fixture(b, "fn", "run")
        p = run / "stats.csv"
        lines = p.read_text().splitlines()
        if kind == "missing columns":
            p.write_text("\n".join(",".join(ln.split(",")[:2]) for ln in lines) + "\n")
        elif kind == "lines shuffled":
            random.Random(3).shuffle(lines)
            p.write_text("\n".join(lines) + "\n")
        elif kind == "header only, no rows":
            p.write_text(lines[0] + "\n")
        else:
            p.write_bytes(os.urandom(3000))
        b.allow = ["plot.png", "plot.svg"]
        r = b.cli("plot", "run", "--out", "plot")
        if kind == "lines shuffled" and r.returncode == 0:
            return "ok"  # read in any order is fine
        return expect_error(r)
    return case


def _history_valid(path: Path) -> tuple[bool, str]:
    import numpy as np

    raw = np.frombuffer(path.read_bytes(), "<f8") if path.stat().st_size % 8 == 0 else None
    if raw is None:
        return False, "size not a multiple of 8"
    i, gens = 0, []
    while i < raw.size:
        if i + 3 > raw.size:
            return False, f"cut at byte {8 * i}"
        g, n, d = raw[i:i + 3]
        if not (n >= 1 and d >= 1 and n == int(n) and d == int(d) and n * d < 1e7):
            return False, f"no header at byte {8 * i}"
        gens.append(int(g))
        i += 3 + int(n) * int(d) + int(n)
    return i == raw.size and gens == sorted(gens), f"generations {gens[:3]}..."


def population_emptied(b: Box) -> str:
    run = fixture(b, "fn", "run")
    (run / "population.bin").write_bytes(b"")
    b.allow = ["run"]
    r = b.cli("resume", "run", "-q", "--set", "run.generations=14")
    if r.returncode != 0:
        return expect_error(r)
    ok, why = _history_valid(run / "population.bin")
    return expect_ok(r, ok, f"population.bin unreadable: {why}")


def newline_name(where: str):
    forged = "stopped: forged at generation 99"

    def case(b: Box) -> str:
        if where == "robot":
            spec = spec_copy(b, {'name = "op3"': f'name = "op3\\n{forged}"'})
            r = robot_run(b, spec)
            log = b.tmp / "out" / "log.txt"
        else:
            out = f"out\n{forged}"
            b.allow = [out]
            r = b.cli("run", "functions", "-q", "--out", out, *FN)
            log = b.tmp / out / "log.txt"
        lines = log.read_text(errors="replace").splitlines() if log.is_file() else []
        if any(ln.startswith(forged) for ln in lines):
            return "SILENT (a forged line in log.txt)"
        if r.returncode == 0:
            return expect_ok(r, True)
        return expect_error(r)
    return case


def cases() -> dict:
    from hostile_cases_31_files import cases as file_cases
    from hostile_cases_31_finish import cases as finish_cases
    from hostile_cases_31_procs import cases as proc_cases
    from hostile_cases_31_readers import cases as reader_cases

    own = {
        "O1 --overwrite on a project folder (config.toml, thesis.tex, src/, .git/)":
            overwrite_project,
        "O2 --overwrite on project/src/.. (the same folder by another path)":
            overwrite_project_path_trick,
        "O3 --overwrite on a symlink to the project folder": overwrite_link_to_project,
        "O4 --overwrite on a run folder with a user file added": overwrite_user_file,
        "O5 --overwrite on an unmarked old-style run folder": overwrite_unmarked,
        "O6 --overwrite, claimed plots/ a symlink to outside/":
            overwrite_claimed_link("outside", "plots"),
        "O7 --overwrite, claimed best.json a symlink to outside/keep.txt":
            overwrite_claimed_link("outside/keep.txt", "best.json"),
        "O8 --overwrite, forged marker naming .., ../outside, /": overwrite_forged_marker,
        "O9 --overwrite on the run's own folder (control)": overwrite_own_run,
        "O10 new run into a non-empty non-run folder": new_run_into("outside"),
        "O11 run --out an existing file": new_run_into("outside/keep.txt"),
        "O12 run --out a FIFO": new_run_into("fifo"),
        "O13 run --out a socket": new_run_into("socket"),
        "O14 run --out /dev/null (private /dev)": new_run_into("/dev/null"),
    }
    accepted = {
        "A1 biped-kick plan --ball nan nan": kick_plan("--ball", "nan", "nan"),
        "A2 biped-kick plan --ball inf 0": kick_plan("--ball", "inf", "0"),
        "A3 biped-kick plan --robot 0 nan 0": kick_plan("--robot", "0", "nan", "0"),
        "A4 humanoid-repertoire export --hold nan": repertoire_hold("nan"),
        "A5 humanoid-repertoire export --hold inf": repertoire_hold("inf"),
        "A6 humanoid-repertoire export --hold -1": repertoire_hold("-1"),
        "A7 humanoid-walk-open-loop compare on a biped-kick run": walk_compare_kick,
        "A8 robot spec clearance_m = 1e300":
            spec_value({"clearance_m = 0.0005": "clearance_m = 1e300"}),
        "A9 quadruped goal inside an obstacle (refused within 8 s)": goal_in_obstacle,
        "A10 plot: stats.csv with missing columns": plot_damaged("missing columns"),
        "A11 plot: stats.csv lines shuffled": plot_damaged("lines shuffled"),
        "A12 plot: stats.csv binary garbage": plot_damaged("binary"),
        "A13 plot: stats.csv header only": plot_damaged("header only, no rows"),
        "A14 ': > population.bin' then resume": population_emptied,
        "A15 robot name with a newline (log.txt forged?)": newline_name("robot"),
        "A16 --out path with a newline (log.txt forged?)": newline_name("out"),
    }
    writes, devnull = file_cases()
    return {**own, **proc_cases(), **writes, **reader_cases(), **accepted, **finish_cases(),
            **devnull}
