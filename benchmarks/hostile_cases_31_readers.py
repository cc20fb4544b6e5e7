"""Issue 31, class 5: readers. Deeply nested JSON and NaN / Infinity / 1e999 in every JSON the
project reads back (a repertoire's index.json, a ``--walk`` repertoire, plan.json,
mission.json, a checkpoint); npz headers declaring huge shapes; a FIFO and ``/dev/zero`` as
every kind of input file; world files with huge bounds, a huge grid, many obstacles; robot
specs with NaN, inf, 1e300 and negative masses; MJCF includes (recursive, ``../outside``,
absolute, 100 MB) and DOCTYPE/ENTITY; a plan with an enormous model; a repertoire with huge
measured steps. A damaged checkpoint must make ``resume`` fall back to the previous one (ok)
or refuse in one line.
"""

from __future__ import annotations

import io
import json
import os
import struct
import zipfile
from pathlib import Path

from hostile_cases_31 import (
    MOTIONS,
    STEP_SMOKE,
    TINY_WORLD,
    fixture,
    q,
    robot_run,
    sets,
    spec_copy,
)
from hostile_harness import Box, Result, SetupError, expect_error, expect_ok

SENTINEL = '"@@HOSTILE@@"'
VALUES = {"deep nesting": "[" * 100_000 + "]" * 100_000, "NaN": "NaN",
          "Infinity": "Infinity", "1e999": "1e999"}


def edit_json(path: Path, put, raw: str) -> None:
    """Set one value of the JSON at ``path`` (``put(obj, value)``) to the raw text ``raw``."""
    obj = json.loads(path.read_text())
    put(obj, "@@HOSTILE@@")
    path.write_text(json.dumps(obj, indent=1).replace(SENTINEL, raw, 1))


def _measured(obj, v):
    obj["entries"][0]["measured"]["dx_m"] = v


def _body(obj, v):
    obj["states"][1]["body"][0] = v


def _generation(obj, v):
    obj["counters"]["generation"] = v


def _latest_checkpoint(run: Path) -> Path:
    name = json.loads((run / "checkpoints" / "latest.json").read_text())["checkpoint"]
    return run / "checkpoints" / name


def _resumed_ok(b: Box, r: Result, run: Path, last: int) -> str:
    """A resume that must continue to generation ``last`` with one stats row per generation."""
    if r.returncode != 0:
        return expect_error(r)
    rows = (run / "stats.csv").read_text().splitlines()[1:]
    gens = [ln.split(",")[0] for ln in rows]
    return expect_ok(r, gens == [str(g) for g in range(last + 1)],
                     f"stats.csv generations {gens[:2]}..{gens[-1:]}")


def json_case(file: str, value: str):
    def case(b: Box) -> str:
        raw = VALUES[value]
        if file in ("index.json", "--walk index.json"):
            run = fixture(b, "rep")
            edit_json(run / "repertoire" / "index.json", _measured, raw)
            if file == "index.json":
                b.allow = ["rep"]
                return expect_error(b.cli("humanoid-repertoire", "walk-to", "rep", "--x", "0.1",
                                          "--json", "--out", "w.motion"))
            return expect_error(b.cli("biped-kick", "play", "--walk", "rep", "--json"))
        if file in ("plan.json", "mission.json"):
            run = fixture(b, "plan" if file == "plan.json" else "mission")
            edit_json(run / file, _body, raw)
            return expect_error(b.cli("quadruped-plan", "check", str(run / file)))
        run = fixture(b, "fn", "run")
        edit_json(_latest_checkpoint(run), _generation, raw)
        b.allow = ["run"]
        r = b.cli("resume", "run", "-q", "--set", "run.generations=14")
        return _resumed_ok(b, r, run, 14)
    return case


def inflate_npz(path: Path, shape=(10**7, 10**7)) -> None:
    """Rewrite every member's .npy header of the npz at ``path`` to declare ``shape``
    (8 * 10^14 bytes as float64); the data stay as they were."""
    out = io.BytesIO()
    with zipfile.ZipFile(path) as z, zipfile.ZipFile(out, "w") as w:
        for info in z.infolist():
            data = z.read(info.filename)
            if data[:6] == b"\x93NUMPY":
                major = data[6]
                n = struct.unpack("<H" if major == 1 else "<I",
                                  data[8:10] if major == 1 else data[8:12])[0]
                start = 10 if major == 1 else 12
                head = data[start:start + n].decode("latin1")
                d = eval(head, {"__builtins__": {}})  # noqa: S307 - numpy's own header text
                d["shape"] = shape if d["shape"] else ()
                text = repr(d)
                pad = 64 - (10 + len(text) + 1) % 64
                hdr = (text + " " * pad + "\n").encode("latin1")
                data = b"\x93NUMPY\x01\x00" + struct.pack("<H", len(hdr)) + hdr + \
                    data[start + n:]
            w.writestr(info.filename, data)
    path.write_bytes(out.getvalue())


def npz_case(kind: str):
    def case(b: Box) -> str:
        if kind == "checkpoint":
            run = fixture(b, "fn", "run")
            meta = json.loads(_latest_checkpoint(run).read_text())
            inflate_npz(run / "checkpoints" / meta.get("arrays_file",
                                                       _latest_checkpoint(run).stem + ".npz"))
            b.allow = ["run"]
            return _resumed_ok(b, b.cli("resume", "run", "-q", "--set", "run.generations=14"),
                               run, 14)
        run = fixture(b, "rep")
        inflate_npz(run / "archive.npz")
        if kind == "export":
            b.allow = ["rep"]
            return expect_error(b.cli("humanoid-repertoire", "export", "rep"))
        b.allow = ["rep"]  # the heat map is drawn only into the run's plots/ (no --out)
        return expect_error(b.cli("plot", "rep"))
    return case


INPUTS = {  # kind: argv(path), extension
    "config.toml (--config)": (lambda p: ["run", "functions", "-q", "--out", "out", "--config",
                                          p], ".toml"),
    ".motion (replay)": (lambda p: ["replay", p, "--json"], ".motion"),
    ".map (problem.map)": (lambda p: ["run", "grid-path", "-q", "--out", "out", "--set",
                                      f"problem.map={q(p)}"], ".map"),
    ".world (problem.world)": (lambda p: ["run", "quadruped-plan", "-q", "--out", "out",
                                          "--set", f"problem.world={q(p)}"], ".world"),
    "robot spec (--robot)": (lambda p: ["run", "humanoid-step", "-q", "--out", "out",
                                        "--robot", p, *STEP_SMOKE], ".toml"),
    "plan.json (check)": (lambda p: ["quadruped-plan", "check", p], ".json"),
    "scenario (arm-ik check)": (lambda p: ["arm-ik", "check", p], ".scen"),
}


def special_input(kind: str, what: str):
    def case(b: Box) -> str:
        b.allow = ["out"]
        if kind == "MJCF named by a spec":
            p = "/dev/zero" if what == "/dev/zero" else str(b.tmp / "robot" / "fifo.xml")
            spec = spec_copy(b, {'mjcf = "op3.xml"': f"mjcf = {q(p)}"})
            if what == "FIFO":
                os.mkfifo(p)
            return expect_error(robot_run(b, spec))
        argv, ext = INPUTS[kind]
        p = "/dev/zero"
        if what == "FIFO":
            p = str(b.tmp / f"input{ext}")
            os.mkfifo(p)
        return expect_error(b.cli(*argv(p)))
    return case


def world_case(kind: str):
    def case(b: Box) -> str:
        text = TINY_WORLD
        if kind == "huge bounds (1e12)":
            text = text.replace("bounds -6 -8 16 9", "bounds -1e12 -1e12 1e12 1e12")
        elif kind == "huge bounds (20 km square)":
            text = text.replace("bounds -6 -8 16 9", "bounds -9999 -9999 9999 9999")
        elif kind == "huge grid (3 km square)":
            text = text.replace("bounds -6 -8 16 9", "bounds -1450 -1450 1450 1450")
        else:  # 490 small squares in a corner: the most polygons a world file may hold
            rows = [f"obstacle {x:.2f} {y:.2f} {x + .01:.2f} {y:.2f} {x + .01:.2f} {y + .01:.2f}"
                    for x in [12 + 0.1 * i for i in range(35)]
                    for y in [-8 + 0.1 * j for j in range(14)]]
            text += "\n".join(rows) + "\n"
        (b.tmp / "w.world").write_text(text)
        b.allow = ["out"]
        r = b.cli("run", "quadruped-plan", "-q", "--out", "out", *sets(
            f"problem.world={q(b.tmp / 'w.world')}", "algorithm.name=receding",
            "run.generations=2", "run.videos=false", "problem.gif_max_frames=4"))
        if kind.startswith("many") and r.returncode in (0, 1) and not r.stderr.strip():
            return expect_ok(Result(r.args, 0, r.stdout, r.stderr, r.wall), True)
        return expect_error(r)
    return case


def spec_case(kind: str):
    edits = {"NaN clearance_m": {"clearance_m = 0.0005": "clearance_m = nan"},
             "inf tilt_rad": {"tilt_rad = 0.785": "tilt_rad = inf"},
             "1e300 fall height_m": {"height_m = 0.18": "height_m = 1e300"}}

    def case(b: Box) -> str:
        if kind == "negative mass (MJCF)":
            spec = spec_copy(b)
            xml = spec.parent / "op3.xml"
            xml.write_text(xml.read_text().replace('mass="1.34928"', 'mass="-1.34928"', 1))
        else:
            spec = spec_copy(b, edits[kind])
        r = robot_run(b, spec)
        if r.returncode == 0 and "Nan, Inf or huge value" in r.stderr:
            return "SILENT (MuJoCo instability warnings)"
        return expect_error(r)
    return case


def mjcf_case(kind: str):
    def case(b: Box) -> str:
        spec = spec_copy(b)
        d = spec.parent
        xml = d / "op3.xml"
        text = xml.read_text()
        harmless = '<custom><numeric name="hostile" data="1"/></custom>'
        (b.tmp / "outside" / "x.xml").write_text(f"<mujoco>{harmless}</mujoco>\n")
        inc = {"recursive include": "loop.xml", "include of ../outside": "../outside/x.xml",
               "absolute include": str(b.tmp / "outside" / "x.xml"),
               "100 MB include": "big.xml"}.get(kind)
        if kind == "recursive include":
            (d / "loop.xml").write_text('<mujoco><include file="loop.xml"/></mujoco>\n')
        elif kind == "100 MB include":
            with open(d / "big.xml", "wb") as fh:
                fh.write(b"<mujoco>\n<!-- ")
                for _ in range(100):
                    fh.write(b" " * (1 << 20))
                fh.write(f" -->\n{harmless}</mujoco>\n".encode())
        head, rest = text.split("<mujoco", 1)
        tag_end = rest.index(">") + 1
        if kind == "DOCTYPE with ENTITY expansion":
            ents = ['<!ENTITY a0 "lollollollollollollollollollol">'] + \
                [f'<!ENTITY a{i} "{("&a" + str(i - 1) + ";") * 10}">' for i in range(1, 10)]
            text = head + "<!DOCTYPE mujoco [" + "".join(ents) + "]>\n<mujoco" + \
                rest[:tag_end].replace('model="', 'model="&a9;', 1) + rest[tag_end:]
        else:
            text = head + "<mujoco" + rest[:tag_end] + f'\n  <include file="{inc}"/>' + \
                rest[tag_end:]
        xml.write_text(text)
        return expect_error(robot_run(b, spec))
    return case


def enormous_model(b: Box) -> str:
    run = fixture(b, "plan")
    obj = json.loads((run / "plan.json").read_text())
    obj["model"]["a"] = obj["model"]["b"] = 1e300
    obj["model"]["hips"] = [[-1e300, 1e300], [-1e300, -1e300], [1e300, -1e300], [1e300, 1e300]]
    (run / "plan.json").write_text(json.dumps(obj))
    b.allow = ["plan"]
    return expect_error(b.cli("quadruped-plan", "simulate", "plan/plan.json", "--json"))


def huge_steps(which: str):
    def case(b: Box) -> str:
        run = fixture(b, "rep")
        p = run / "repertoire" / "index.json"
        obj = json.loads(p.read_text())
        for i, e in enumerate(obj["entries"]):
            if which == "every step" or i == 0:
                e["measured"] = {k: 1e300 for k in e["measured"]}
        p.write_text(json.dumps(obj))
        return _walk_to(b)
    return case


def _walk_to(b: Box) -> str:
    b.allow = ["rep", "w.motion"]
    return expect_error(b.cli("humanoid-repertoire", "walk-to", "rep", "--x", "0.1", "--json",
                              "--out", "w.motion"))


def cases() -> dict:
    if not MOTIONS.is_dir():
        raise SetupError("no bundled motions")
    out = {}
    for file in ("index.json", "--walk index.json", "plan.json", "mission.json",
                 "checkpoint JSON"):
        for value in VALUES:
            out[f"R {file}: {value}"] = json_case(file, value)
    out["R archive.npz declaring 10^7 x 10^7: repertoire export"] = npz_case("export")
    out["R archive.npz declaring 10^7 x 10^7: plot"] = npz_case("plot")
    out["R checkpoint npz declaring 10^7 x 10^7: resume falls back"] = npz_case("checkpoint")
    for kind in [*INPUTS, "MJCF named by a spec"]:
        for what in ("FIFO", "/dev/zero"):
            out[f"R {what} as {kind}"] = special_input(kind, what)
    for kind in ("huge bounds (1e12)", "huge bounds (20 km square)", "huge grid (3 km square)",
                 "many obstacles (490, the most allowed)"):
        out[f"R .world with {kind}"] = world_case(kind)
    for kind in ("NaN clearance_m", "inf tilt_rad", "1e300 fall height_m",
                 "negative mass (MJCF)"):
        out[f"R robot spec: {kind}"] = spec_case(kind)
    for kind in ("recursive include", "include of ../outside", "absolute include",
                 "100 MB include", "DOCTYPE with ENTITY expansion"):
        out[f"R MJCF: {kind}"] = mjcf_case(kind)
    out["R plan.json with an enormous model: simulate"] = enormous_model
    out["R repertoire, every step measured 1e300 m: walk-to"] = huge_steps("every step")
    out["R repertoire, one step measured 1e300 m: walk-to"] = huge_steps("one step")
    return out
