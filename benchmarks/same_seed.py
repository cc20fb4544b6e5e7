"""Same results before and after a change: every study, the robot runs and the seed
experiments, run through the public CLI of two trees with the same seeds, their output files
compared (timing aside), with the time ratio of each case.

Each case is one or more ``evomotion`` command lines, run in a fresh folder per tree by the
tree's own console entry point (``[project.scripts] evomotion`` of its ``pyproject.toml``,
called with the tree's ``src`` first on ``PYTHONPATH``), so module renames inside ``src`` do
not matter. Cases (``--list`` prints them with their commands):

- ``run/<study>/default`` and ``run/<study>/<preset>``: ``evomotion run`` of every registered
  study with its defaults and with its paper preset (``--preset seed``; humanoid-walk-open-loop's
  ``nominal`` and humanoid-repertoire's ``map_elites``, which have none), 3 generations (1 for
  the MuJoCo studies and the closed-loop ones: gym, humanoid-balance, humanoid-walk), videos
  off, no wall-clock budget; functions once per method (ga, cga,
  cmaes; map_elites and cma_me with ``problem.measures=linear_projection``). Some add the
  study's deterministic follow-up commands on the run folder: ``grid-path make-map``,
  ``humanoid-walk-open-loop compare --json``, ``humanoid-repertoire pick / walk-to --json``,
  ``biped-kick
  play --json``, ``quadruped-plan check / simulate --json``, ``humanoid-balance compare`` and
  ``humanoid-walk compare`` on 2 worlds ``--json``.
- ``robot/<robot>/<study>``: ``--robot op3`` for humanoid-step, humanoid-walk-open-loop,
  humanoid-repertoire and biped-kick (a tree that refuses it compares by its one-line error),
  ``--robot dm-humanoid`` for the first three, ``--robot dm-quadruped`` for humanoid-walk-open-loop
  with its ``nominal`` preset (the step needs a biped; the 8-world walk takes minutes).
- ``study/...``: the seed experiments with small settings: ``grid-path study`` (seed and
  beyond), ``arm-ik study --wall-seconds 0``, ``humanoid-step study --quick``, ``biped-kick
  study``, ``quadruped-plan study --astar`` (expansion budgets, never a time budget).
  ``quadruped-plan missions`` is left out: its replans have a time budget.
- ``internal/<study>``: the 58 outputs of the former comparison through the studies' internal
  functions (``same_seed_internal.py``), skipped when a tree no longer has them.

Compared: every file the commands write (best.json, stats.csv, checkpoints, config.toml,
plans, tables, ``.motion``, ``.npz``, JSON results; see ``same_seed_compare.py`` for what is
left out as timing), their stdout, and their exit status (a refusal by its ``error:`` line).

    python benchmarks/same_seed.py --baseline 1b16360 [--tree REV] [--cases 'run/*,study/*']
                                   [--repeat 2] [--keep DIR] [--list]
                                   [--rename seed_example=paper_example ...]

``--tree REV`` compares two exported revisions (``--tree 1b16360 --baseline 1b16360`` checks
the script: every case identical); without it, "this tree" is the working tree. ``--rename
OLD=NEW`` reads a name renamed on purpose in the baseline's outputs as the new one, so that a
case differs only where a result does. The table gives per case whether everything compared is
identical (``yes``; ``refused``: both trees end in the same ``error:`` line; ``skipped``: an
internal case a tree lacks), the first difference (best.json, stats.csv and exit statuses
first, then how many more files differ), the minimum seconds of each tree over ``--repeat``
interleaved runs and their ratio; a summary line follows.
"""

from __future__ import annotations

import argparse
import fnmatch
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from baseline import ROOT, export  # noqa: E402
from same_seed_compare import Paths, first_difference, folder_values, stdout_value  # noqa: E402

INTERNAL = Path(__file__).with_name("same_seed_internal.py")
LOG_PREFIX = "same-seed-command-"  # each command's stdout and stderr, kept with --keep
MUJOCO = {"humanoid-step", "humanoid-walk-open-loop", "humanoid-repertoire", "biped-kick",
          "gym", "humanoid-balance", "humanoid-walk"}
#: each study's paper preset (None: the study has none); the last three are the closed-loop
#: policy studies (issues 33, 34)
PRESETS = {"grid-path": "seed", "humanoid-step": "seed", "humanoid-walk-open-loop": "nominal",
           "humanoid-repertoire": "map_elites", "arm-ik": "seed", "biped-kick": "seed",
           "quadruped-plan": "seed", "gym": "paper", "humanoid-balance": None,
           "humanoid-walk": None}
FOLLOW_UP = {  # deterministic commands on the default run folder ("out")
    "grid-path": [["grid-path", "make-map", "random.map", "--seed", "3"]],
    "humanoid-walk-open-loop": [["humanoid-walk-open-loop", "compare", "out", "--json"]],
    "humanoid-repertoire": [["humanoid-repertoire", "pick", "out", "--dx", "0.05", "--json"],
                            ["humanoid-repertoire", "walk-to", "out", "--x", "0.3", "--json",
                             "--out", "walk.motion"]],
    "biped-kick": [["biped-kick", "play", "--kick", "out", "--json"]],
    "quadruped-plan": [["quadruped-plan", "check", "out"],
                       ["quadruped-plan", "simulate", "out", "--json"]],
    "humanoid-balance": [["humanoid-balance", "compare", "out", "--worlds", "2", "--json"]],
    "humanoid-walk": [["humanoid-walk", "compare", "out", "--worlds", "2", "--duration", "2",
                       "--json"]],
}


@dataclass
class Case:
    name: str
    commands: list[list[str]] = field(default_factory=list)
    internal: str = ""  # a group of same_seed_internal.py instead of commands


def run_args(study: str, *extra: str) -> list[str]:
    gens = 1 if study in MUJOCO else 3
    return ["run", study, "--out", "out", "-q", "--set", "run.seed=0",
            "--set", f"run.generations={gens}", "--set", "run.videos=false",
            "--set", "run.wall_seconds=0", *extra]


def cases() -> list[Case]:
    out = [Case("run/functions/default", [run_args("functions")])]
    out += [Case(f"run/functions/{m}", [run_args("functions", "--set", f"algorithm.name={m}")])
            for m in ("cga", "cmaes")]
    out += [Case(f"run/functions/{m}", [run_args("functions", "--set", f"algorithm.name={m}",
                                                 "--set", "problem.measures=linear_projection")])
            for m in ("map_elites", "cma_me")]  # quality diversity needs measures
    for study, preset in PRESETS.items():
        out.append(Case(f"run/{study}/default", [run_args(study), *FOLLOW_UP.get(study, [])]))
        if preset:
            out.append(Case(f"run/{study}/{preset}", [run_args(study, "--preset", preset)]))
    robots = [("op3", s) for s in ("humanoid-step", "humanoid-walk-open-loop",
                                    "humanoid-repertoire",
                                   "biped-kick")]
    robots += [("dm-humanoid", s) for s in ("humanoid-step", "humanoid-walk-open-loop",
                                            "humanoid-repertoire")]
    out += [Case(f"robot/{r}/{s}", [run_args(s, "--robot", r)]) for r, s in robots]
    out.append(Case("robot/dm-quadruped/humanoid-walk-nominal",  # its trot; 8 worlds: minutes
                    [run_args("humanoid-walk-open-loop", "--robot", "dm-quadruped", "--preset",
                              "nominal")]))
    out += [
        Case("study/grid-path/seed", [["grid-path", "study", "--seeds", "2", "--generations",
                                       "5", "--map", "seed10a", "--map", "seed20"]]),
        Case("study/grid-path/beyond", [["grid-path", "study", "--experiment", "beyond",
                                         "--seeds", "1", "--n-maps", "1", "--pop", "20",
                                         "--generations", "5"]]),
        Case("study/arm-ik", [["arm-ik", "study", "--seeds", "2", "--wall-seconds", "0",
                               "--scenario", "seed_example", "--scenario", "corridor"]]),
        Case("study/humanoid-step", [["humanoid-step", "study", "--out", "out", "--quick",
                                      "--workers", "1"]]),
        Case("study/biped-kick", [["biped-kick", "study", "--out", "out", "--budget", "10",
                                   "--kicks", "2", "--aim", "0"]]),
        Case("study/quadruped-plan", [["quadruped-plan", "study", "--max-expansions", "2000",
                                       "--astar", "--astar-seconds", "600"]]),
    ]
    out += [Case(f"internal/{g}", internal=g) for g in ("grid-path", "arm-ik", "quadruped-plan")]
    return out


def select(all_cases: list[Case], patterns: str | None) -> list[Case]:
    """Cases matching any comma-separated glob (a pattern without ``*?[`` matches as a
    substring)."""
    if not patterns:
        return all_cases
    pats = [p if any(c in p for c in "*?[") else f"*{p}*" for p in patterns.split(",") if p]
    return [c for c in all_cases if any(fnmatch.fnmatchcase(c.name, p) for p in pats)]


@dataclass
class Tree:
    """One side of the comparison: a ``src`` folder and its console entry point."""

    label: str
    src: Path
    entry: str  # "module:function"

    @classmethod
    def at(cls, rev: str | None, into: Path) -> Tree:
        if rev is None:
            root, label = ROOT, "working tree"
        else:
            into.mkdir(parents=True)
            export(rev, into, ("src", "pyproject.toml"))
            root, label = into, rev
        scripts = tomllib.loads((root / "pyproject.toml").read_text())["project"]["scripts"]
        return cls(label, (root / "src").resolve(), scripts["evomotion"])

    def command(self, args: list[str]) -> list[str]:
        mod, fn = self.entry.split(":")
        code = (f"import sys; from {mod} import {fn} as main; "
                "sys.argv = ['evomotion', *sys.argv[1:]]; sys.exit(main())")
        return [sys.executable, "-c", code, *args]

    def env(self) -> dict[str, str]:
        return dict(os.environ, PYTHONPATH=str(self.src), MPLBACKEND="Agg", COLUMNS="200",
                    NO_COLOR="1", TERM="dumb")


def run_case(case: Case, tree: Tree, folder: Path, timeout: float,
             renames: dict[str, str] | None = None) -> tuple[dict, float]:
    """Run ``case`` with ``tree`` in the empty ``folder``; its compared values (``renames``
    applied) and seconds."""
    folder.mkdir(parents=True)
    paths = Paths(folder.resolve(), tree.src, renames)
    values: dict = {}
    t0 = time.perf_counter()
    if case.internal:
        res = json.loads(_internal(case.internal, tree, folder, timeout))
        if "skipped" in res:
            return {"skipped": res["skipped"]}, res["seconds"]
        return {"outputs": res["outputs"]}, res["seconds"]
    logs = {}
    for i, args in enumerate(case.commands):
        try:
            p = subprocess.run(tree.command(args), cwd=folder, env=tree.env(),
                               capture_output=True, text=True, timeout=timeout)
            rc, err = p.returncode, p.stderr.strip().splitlines()
            values[f"command {i + 1} stdout"] = stdout_value(p.stdout, paths)
            logs[f"{LOG_PREFIX}{i + 1}.txt"] = f"$ {args}\n{p.stdout}\n--- stderr\n{p.stderr}"
        except subprocess.TimeoutExpired:
            rc, err = "timeout", []
        values[f"command {i + 1} exit"] = rc
        if rc != 0:  # exit 3 without a message: a run that ended unsolved (arm-ik)
            last = paths(err[-1]) if err else ""
            values[f"command {i + 1} error"] = last
            if rc == "timeout" or last.startswith("error"):
                break  # the next commands need this one's output
    seconds = time.perf_counter() - t0
    values.update(folder_values(folder, paths))
    for name, text in logs.items():  # for --keep; not compared (stderr holds notes, times)
        (folder / name).write_text(text)
    return values, seconds


def _internal(group: str, tree: Tree, folder: Path, timeout: float) -> str:
    out = folder / "internal.json"
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, str(INTERNAL), "--child", str(out), "--group", group],
                       cwd=folder, env=tree.env(), capture_output=True, text=True,
                       timeout=timeout)
    if p.returncode != 0:  # a crash is a result to compare, not the end of the comparison
        err = p.stderr.strip().splitlines()
        return json.dumps({"outputs": {"exit": p.returncode, "error": err[-1] if err else ""},
                           "seconds": time.perf_counter() - t0})
    return out.read_text()


RESULTS = ("best.json", "stats.csv", "exit", "error", "outputs")  # shown first when they differ


def verdict(old: dict, new: dict) -> tuple[str, str]:
    """(identical, first difference) of one case: the first differing value of the first
    differing file (best.json, stats.csv and exit statuses before the others), and how many
    more files differ."""
    if "skipped" in old or "skipped" in new:
        why = old.get("skipped") or new.get("skipped")
        side = "baseline" if "skipped" in old else "this tree"
        return "skipped", f"{side}: {why}"[:160]
    keys = list(old) + [k for k in new if k not in old]
    differ = sorted((k for k in keys if first_difference({k: old.get(k)}, {k: new.get(k)})),
                    key=lambda k: (not k.endswith(RESULTS), keys.index(k)))
    if not differ:
        errors = [f"{k}: {v}" for k, v in old.items()
                  if k.endswith(" error") and str(v).startswith("error")]
        return ("refused", f"both: {errors[0]}"[:160]) if errors else ("yes", "")
    k = differ[0]
    d = first_difference({k: old[k]}, {k: new[k]}) if k in old and k in new else \
        f"{k}: only in {'the baseline' if k in old else 'this tree'}"
    more = f" (and {len(differ) - 1} more: {', '.join(differ[1:4])}" + \
        (", ...)" if len(differ) > 4 else ")") if len(differ) > 1 else ""
    return "no", f"{d}{more}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", default="HEAD", help="git revision to compare against")
    ap.add_argument("--tree", default=None,
                    help="git revision as 'this tree' (default: the working tree)")
    ap.add_argument("--cases", default=None, help="comma-separated globs / substrings")
    ap.add_argument("--list", action="store_true", help="print the cases and exit")
    ap.add_argument("--repeat", type=int, default=1, help="runs per case and tree (timing)")
    ap.add_argument("--timeout", type=float, default=900, help="seconds per command")
    ap.add_argument("--keep", type=Path, default=None, help="keep the case folders here")
    ap.add_argument("--rename", action="append", default=[], metavar="OLD=NEW",
                    help="read the name OLD in the baseline's outputs as NEW (a renamed "
                         "scenario, preset, key: not a changed result); repeatable")
    a = ap.parse_args()
    if any("=" not in r or r.startswith("=") for r in a.rename):
        sys.exit("error: --rename: expected OLD=NEW")
    chosen = select(cases(), a.cases)
    if a.list:
        for c in chosen:
            cmds = [f"same_seed_internal.py --group {c.internal}"] if c.internal else \
                [" ".join(["evomotion", *x]) for x in c.commands]
            print(f"{c.name}\n" + "".join(f"    {x}\n" for x in cmds), end="")
        return
    if not chosen:
        sys.exit(f"error: no case matches {a.cases!r} (see --list)")
    if a.keep is not None and a.keep.exists():
        sys.exit(f"error: --keep {a.keep}: already exists")
    work = Path(tempfile.mkdtemp(prefix="same-seed-")) if a.keep is None else a.keep
    try:
        compare(a, chosen, work)
    finally:
        if a.keep is None:
            shutil.rmtree(work, ignore_errors=True)


def compare(a: argparse.Namespace, chosen: list[Case], work: Path) -> None:
    old_tree = Tree.at(a.baseline, work / "trees" / "baseline")
    new_tree = Tree.at(a.tree, work / "trees" / "this")
    print(f"baseline {old_tree.label} ({old_tree.entry}) vs this tree {new_tree.label} "
          f"({new_tree.entry}): {len(chosen)} cases, repeat {a.repeat}"
          + "".join(f"; {r} read as renamed" for r in a.rename), flush=True)
    print("| case | identical | first difference | baseline s | this tree s | ratio |\n"
          "|---|---|---|---|---|---|", flush=True)
    counts: dict[str, int] = {}
    tot_old = tot_new = 0.0
    for case in chosen:
        slug = case.name.replace("/", "__")
        old_s, new_s, old, new = [], [], {}, {}
        for r in range(a.repeat):  # interleaved, so both see the same load
            o, to = run_case(case, old_tree, work / f"r{r}" / "baseline" / slug, a.timeout,
                             dict(x.split("=", 1) for x in a.rename))
            n, tn = run_case(case, new_tree, work / f"r{r}" / "this" / slug, a.timeout)
            old, new = (o, n) if r == 0 else (old, new)
            old_s.append(to)
            new_s.append(tn)
        same, diff = verdict(old, new)
        counts[same] = counts.get(same, 0) + 1
        to, tn = min(old_s), min(new_s)
        tot_old, tot_new = tot_old + to, tot_new + tn
        print(f"| {case.name} | {same} | {diff.replace('|', '/')} | {to:.2f} | {tn:.2f} | "
              f"{tn / to if to else float('nan'):.2f} |", flush=True)
    print(f"\nsummary: {len(chosen)} cases, {counts.get('yes', 0)} identical, "
          f"{counts.get('no', 0)} differ, {counts.get('refused', 0)} refused by both trees "
          f"alike, {counts.get('skipped', 0)} skipped; "
          f"{tot_old:.1f} s baseline, {tot_new:.1f} s this tree "
          f"(ratio {tot_new / tot_old if tot_old else float('nan'):.2f})")
    if a.keep is not None:
        print(f"case folders kept in {work}")


if __name__ == "__main__":
    main()
