"""Run folders that cannot be corrupted, checkpoints that are checked (issue 12)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.run.config import resolve_config
from evomotion.run.faults import fault_at
from evomotion.run.lock import RunLock
from evomotion.run.runner import EXIT_NO_FINITE, run_study

sys.path.insert(0, str(Path(__file__).parent))
from cluster_helpers import assert_same_run  # noqa: E402
from toy_study import STUDY as TOY  # noqa: E402

HERE = Path(__file__).parent
NEWEST = "gen-000009"  # the Ctrl-C checkpoint of the interrupted run (step 10 was cut)
PREVIOUS = "gen-000008"
SETS = ["run.generations=12", "run.checkpoint_every=4", "problem.raise_above=9"]


def _interrupted(out: Path, cut: int = 10, sets=SETS) -> None:
    """A toy run interrupted (Ctrl-C) during step ``cut``: checkpoints at 0, 4, 8 and 9."""
    with fault_at(cut, "interrupt"):
        res = run_study(TOY, resolve_config(TOY, None, sets), out, quiet=True)
    assert res.stop_reason == "interrupted"


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("ref") / "full"
    run_study(TOY, resolve_config(TOY, None, SETS), out, quiet=True)
    return out


@pytest.fixture(scope="module")
def interrupted(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("cut") / "cut"
    _interrupted(out)
    return out


def _resume(d: Path) -> str:
    run_study(TOY, resolve_config(TOY, None, SETS), d, quiet=True, resume=True)
    return (d / "log.txt").read_text()


def _set(path: Path, key: str, value) -> None:
    meta = json.loads(path.read_text())
    node = meta
    *parents, leaf = key.split(".")
    for p in parents:
        node = node[p]
    if value is KeyError:
        del node[leaf]
    else:
        node[leaf] = value
    path.write_text(json.dumps(meta))


def _damage_truncated_json(ck: Path) -> None:
    p = ck / f"{NEWEST}.json"
    p.write_bytes(p.read_bytes()[:40])


def _damage_truncated_npz(ck: Path) -> None:
    p = ck / f"{NEWEST}.npz"
    p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])


def _damage_garbage_npz(ck: Path) -> None:
    (ck / f"{NEWEST}.npz").write_bytes(os.urandom(4096))


def _damage_cut_population(ck: Path) -> None:
    p = ck / f"{NEWEST}.npz"
    with np.load(p) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["state.pop"] = arrays["state.pop"][:5]
    arrays["state.cost"] = arrays["state.cost"][:5]
    np.savez(p, **arrays)


DAMAGE = {
    "truncated latest.json": lambda ck: (ck / "latest.json").write_text('{"checkp'),
    "truncated checkpoint JSON": _damage_truncated_json,
    "truncated npz": _damage_truncated_npz,
    "garbage npz": _damage_garbage_npz,
    "missing field": lambda ck: _set(ck / f"{NEWEST}.json", "counters.evaluations", KeyError),
    "string for a number": lambda ck: _set(ck / f"{NEWEST}.json", "counters.generation", "8"),
    "population cut to 5 rows": _damage_cut_population,
    "stats_offset past the end": lambda ck: _set(ck / f"{NEWEST}.json",
                                                 "counters.stats_offset", 49_800_000),
    "stats_offset inside a line": lambda ck: _set(ck / f"{NEWEST}.json",
                                                  "counters.stats_offset", 7),
    "arrays_file outside the folder": lambda ck: _set(ck / f"{NEWEST}.json", "arrays_file",
                                                      "../../other/gen-000020.npz"),
    "rng state garbage": lambda ck: _set(ck / f"{NEWEST}.json", "rng.state", {"x": 1}),
    "NaN wall time": lambda ck: _set(ck / f"{NEWEST}.json", "counters.wall_s", float("nan")),
}


@pytest.mark.parametrize("kind", sorted(DAMAGE))
def test_damaged_newest_checkpoint_falls_back_and_results_match(kind, interrupted, reference,
                                                                tmp_path):
    d = tmp_path / "run"
    shutil.copytree(interrupted, d)
    DAMAGE[kind](d / "checkpoints")
    size_before = (d / "stats.csv").stat().st_size
    log = _resume(d)
    if kind == "truncated latest.json":  # the checkpoint files themselves are intact
        assert "skipped" not in log
    else:
        assert NEWEST + ".json" in log and "skipped" in log
        assert f"resuming from the newest valid checkpoint, checkpoints/{PREVIOUS}.json" in log
    assert (d / "stats.csv").stat().st_size < 10 * size_before  # no NUL padding
    assert b"\0" not in (d / "stats.csv").read_bytes()
    assert_same_run(reference, d)


def test_every_checkpoint_damaged_is_one_line_error(interrupted, tmp_path):
    d = tmp_path / "run"
    shutil.copytree(interrupted, d)
    for p in (d / "checkpoints").glob("gen-*.npz"):
        p.write_bytes(b"not a zip")
    with pytest.raises(InputError, match="no valid checkpoint to resume from") as e:
        _resume(d)
    assert "\n" not in str(e.value)


def test_resume_refuses_a_changed_seed_or_problem(interrupted, tmp_path):
    d = tmp_path / "run"
    shutil.copytree(interrupted, d)
    for item, key in (("run.seed=99", "run.seed"), ("problem.nan_above=1.0",
                                                    "problem.nan_above")):
        cfg = resolve_config(TOY, None, [*SETS, item])
        with pytest.raises(InputError, match=f"resume cannot change {key}"):
            run_study(TOY, cfg, d, quiet=True, resume=True)


def test_leftover_temporaries_are_removed(interrupted, reference, tmp_path):
    d = tmp_path / "run"
    shutil.copytree(interrupted, d)
    (d / "checkpoints" / ".gen-000012.npz.k3j_9x0q.tmp").write_bytes(b"half")
    log = _resume(d)
    assert "removed 1 temporary file" in log
    assert not list((d / "checkpoints").glob("*.tmp"))
    assert_same_run(reference, d)


def test_second_run_into_a_run_folder_is_refused(reference, tmp_path):
    d = tmp_path / "run"
    shutil.copytree(reference, d)
    before = (d / "stats.csv").read_bytes()
    with pytest.raises(InputError, match="already holds a run"):
        run_study(TOY, resolve_config(TOY, None, SETS), d, quiet=True)
    assert (d / "stats.csv").read_bytes() == before
    run_study(TOY, resolve_config(TOY, None, SETS), d, quiet=True, overwrite=True)
    assert_same_run(reference, d)


SLOW_RUN = textwrap.dedent("""
    import sys
    sys.path.insert(0, sys.argv[2])
    from toy_study import STUDY
    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study
    run_study(STUDY, resolve_config(STUDY, None, ["run.generations=15", "problem.sleep_s=0.1",
              "problem.raise_above=9"]), sys.argv[1], quiet=True)
""")


def test_two_concurrent_runs_on_one_folder(tmp_path):
    d = tmp_path / "run"
    first = subprocess.Popen([sys.executable, "-c", SLOW_RUN, str(d), str(HERE)])
    try:
        for _ in range(300):
            if (d / "run.lock").exists() and '"pid"' in (d / "run.lock").read_text():
                break
            time.sleep(0.05)
        with pytest.raises(InputError, match="another run is writing|already holds a run"):
            run_study(TOY, resolve_config(TOY, None, ["run.generations=3"]), d, quiet=True,
                      overwrite=True)
        with pytest.raises(InputError, match="another run is writing"):
            RunLock(d).acquire()
    finally:
        assert first.wait(timeout=120) == 0
    rows = (d / "stats.csv").read_text().splitlines()
    assert len(rows) == 1 + 16 and [r.split(",")[0] for r in rows[1:]] == \
        [str(g) for g in range(16)]
    assert (d / "run.lock").read_text() == ""  # released cleanly


def test_stale_lock_of_a_dead_process_is_taken_over(interrupted, reference, tmp_path):
    d = tmp_path / "run"
    shutil.copytree(interrupted, d)
    (d / "run.lock").write_text("pid 999999 on elsewhere\n")
    log = _resume(d)
    assert "took over the run folder's lock from pid 999999 on elsewhere" in log
    assert_same_run(reference, d)


def test_run_without_any_finite_fitness_writes_null_and_fails(tmp_path):
    cfg = resolve_config(TOY, None, ["run.generations=2", "problem.nan_above=-10",
                                     "problem.raise_above=9"])
    res = run_study(TOY, cfg, tmp_path / "run", quiet=True)
    assert res.exit_code == EXIT_NO_FINITE
    best = json.loads((tmp_path / "run" / "best.json").read_text())  # valid JSON
    assert best["fitness"] is None
    assert "no individual got a finite fitness" in (tmp_path / "run" / "log.txt").read_text()


@pytest.mark.parametrize("out,msg", [
    ("/proc/evomotion-x", "cannot create the run folder"),
    ("/dev/null/x", "cannot create the run folder"),
    ("FILE", "expected a folder, found a file"),
])
def test_bad_out_is_one_line(out, msg, tmp_path):
    if out == "FILE":
        out = str(tmp_path / "f")
        Path(out).write_text("x")
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "functions", "--out",
                        out, "-q"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and msg in r.stderr and "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


def test_checkpoint_json_is_not_a_zip_bomb_target(interrupted, tmp_path):
    """An npz with an entry that is not a npy array is refused, not loaded with pickle."""
    d = tmp_path / "run"
    shutil.copytree(interrupted, d)
    with zipfile.ZipFile(d / "checkpoints" / f"{NEWEST}.npz", "w") as z:
        z.writestr("state.pop.npy", b"\x93NUMPY garbage")
    log = _resume(d)
    assert NEWEST + ".json" in log and "skipped" in log


def test_a_resume_keeps_the_stopped_sessions_log_lines(tmp_path):
    """The log is the run's history (issue 35): after a Ctrl-C and a resume it still holds the
    ``stopped: interrupted`` line, and the resume says which lines the stopped session wrote
    after the checkpoint it continues from; a last line a kill cut short is ended first."""
    out = tmp_path / "run"
    _interrupted(out)
    before = (out / "log.txt").read_text()
    assert "stopped: interrupted at generation 9" in before
    with open(out / "log.txt", "a") as f:
        f.write("half a li")  # as a kill -9 in the middle of a write leaves it
    text = _resume(out)
    assert text.startswith(before + "half a li\n")
    lines = text.splitlines()
    resumed = [ln for ln in lines if ln.startswith("resumed at generation 9")]
    assert len(resumed) == 1 and "lines above since that checkpoint are the stopped " \
        "session's" in resumed[0]
    assert lines[-1].startswith("stopped: generations at generation 12")
