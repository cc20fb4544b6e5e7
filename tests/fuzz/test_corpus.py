"""Every hand-made bad file in tests/corpus/<reader>/ is a one-line FileFormatError naming the
file and (where there is one) the line; a few of them also through the CLI (exit 2)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from fuzz_readers import CORPUS, READERS

from evomotion.errors import FileFormatError

EXPECTED: dict[str, dict] = json.loads((CORPUS / "readers-expected.json").read_text())


def test_corpus_is_complete():
    on_disk = {f"{d.name}/{p.name}" for d in CORPUS.iterdir() if d.name in READERS
               for p in d.iterdir()}
    assert on_disk == set(EXPECTED) and len(EXPECTED) >= 80


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_bad_file_is_one_line_error(name):
    path = CORPUS / name
    want = EXPECTED[name]
    with pytest.raises(FileFormatError) as e:
        READERS[name.split("/")[0]](path)
    msg = str(e.value)
    where = f"{path}:{want['line']}: " if want["line"] is not None else f"{path}: "
    assert msg.startswith(where), msg
    assert e.value.line == want["line"] and e.value.path == str(path)
    assert want["contains"] in msg, msg
    assert "\n" not in msg and "\r" not in msg and len(msg) < len(str(path)) + 240


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "evomotion.cli", *args], capture_output=True,
                          text=True, timeout=300)


@pytest.mark.parametrize(("args", "name"), [
    (["replay", "{}"], "motion/007-nan-value.motion"),
    (["replay", "{}"], "motion/011-huge-time.motion"),
    (["replay", "{}"], "motion/021-non-utf8-pose-name.motion"),
    (["arm-ik", "check", "{}"], "scenario/004-width-overflow.scen"),
    (["arm-ik", "check", "{}"], "scenario/019-non-utf8.scen"),
    (["quadruped-plan", "check", "{}"], "plan/001-goal-string.json"),
    (["quadruped-plan", "check", "{}"], "plan/039-deep-nesting.json"),
    (["run", "grid-path", "--set", "problem.map='{}'"], "movingai/002-height-zero.map"),
    (["run", "grid-path", "--set", "problem.map='{}'"], "binary/011-non-utf8.txt"),
])
def test_cli_reports_one_error_line(args, name, tmp_path):
    path = CORPUS / name
    r = subprocess.run([sys.executable, "-m", "evomotion.cli",
                        *(a.format(path) for a in args)], capture_output=True, text=True,
                       timeout=300, cwd=tmp_path)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2, r.stderr
    assert len(lines) == 1 and lines[0].startswith(f"error: {path}"), r.stderr
    assert EXPECTED[name]["contains"] in lines[0] and "Traceback" not in r.stderr


def test_cli_directory_without_a_plan(tmp_path):
    r = _cli("quadruped-plan", "check", str(tmp_path))
    assert r.returncode == 2 and r.stderr.strip().startswith(
        f"error: {tmp_path}: expected a plan file or a run folder with plan.json or "
        "mission.json"), r.stderr


@pytest.mark.parametrize("reader", sorted(READERS))
def test_directory_missing_and_oversize_files(reader, tmp_path, monkeypatch):
    import evomotion.textio as textio

    missing = "expected an existing|bundled name"  # a scenario may also be a bundled name
    for path, words in ((tmp_path, "got a directory"), (tmp_path / "nope", missing)):
        with pytest.raises(FileFormatError, match=words) as e:
            READERS[reader](path)
        assert str(e.value).startswith(f"{path}: ") and "\n" not in str(e.value)
    big = tmp_path / "big"
    big.write_bytes(b"0" * 100)
    real = textio.read_file_bytes
    monkeypatch.setattr(textio, "read_file_bytes", lambda p, what, _max: real(p, what, 10))
    for mod in ("evomotion.sim.motion", "evomotion.studies.arm_ik.scenario",
                "evomotion.studies.grid_path.maps", "evomotion.studies.quadruped_plan.plans.plan",
                "evomotion.textio"):
        monkeypatch.setattr(f"{mod}.read_file_bytes", textio.read_file_bytes)
    with pytest.raises(FileFormatError, match="of at most 10 bytes, got 100 bytes"):
        READERS[reader](big)
