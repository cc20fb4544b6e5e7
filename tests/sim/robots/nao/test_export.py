"""Exports for a real NAO (issue 13, part 4): checks, NAOqi script, JSON keyframes, CLI."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from evomotion.errors import FileFormatError, InputError
from evomotion.sim.motion import NAO_JOINT_NAMES, Motion, read_motion
from evomotion.sim.robots.nao.export import (
    export_motion,
    keyframes_json,
    naoqi_plan,
    naoqi_script,
    parse_keyframes,
    read_keyframes,
)
from evomotion.sim.robots.nao.joint_limits import (
    JOINT_RANGES,
    SPEED_LIMITS,
    LimitError,
    check_motion,
)
from fixture_files import WEBOTS_MOTIONS

FIXTURES = WEBOTS_MOTIONS
NAN = np.nan

#: A fake ``naoqi`` module: ALProxy records every call to the JSON file $FAKE_NAOQI_LOG.
FAKE_NAOQI = textwrap.dedent("""
    import json, os

    class ALProxy(object):
        def __init__(self, *args):
            self._calls = [["ALProxy", list(args)]]

        def __getattr__(self, name):
            def call(*args):
                self._calls.append([name, list(args)])
                with open(os.environ["FAKE_NAOQI_LOG"], "w") as f:
                    json.dump(self._calls, f)
            return call
""")


def legs(times_ms, rows, joints=("RHipPitch", "RKneePitch", "RAnklePitch")) -> Motion:
    return Motion(tuple(joints), np.array(times_ms), np.array(rows, dtype=float))


def same(a: Motion, b: Motion) -> None:
    assert a.joints == b.joints
    assert a.times_ms.tolist() == b.times_ms.tolist()
    np.testing.assert_array_equal(a.values, b.values)  # NaN == NaN here; exact otherwise


# ---- limits -------------------------------------------------------------------------------

def test_limits_cover_every_nao_joint_and_match_the_reference():
    assert set(JOINT_RANGES) == NAO_JOINT_NAMES
    assert set(SPEED_LIMITS) == NAO_JOINT_NAMES - {"LHand", "RHand"}
    assert JOINT_RANGES["RKneePitch"] == (-0.102974, 2.120051)  # nao-h25.md 1.4
    assert JOINT_RANGES["LAnkleRoll"] == (-0.397761, 0.768992)
    assert (SPEED_LIMITS["RKneePitch"], SPEED_LIMITS["LHipRoll"]) == (6.40, 4.16)  # walking.md 3
    assert (SPEED_LIMITS["LShoulderPitch"], SPEED_LIMITS["RElbowRoll"]) == (8.27, 7.19)
    assert all(lo < hi for lo, hi in JOINT_RANGES.values())


def test_range_violation_is_one_line_naming_joint_time_value_range():
    m = legs([0, 400, 800], [[-0.5, 1.0, -0.5], [-0.5, 1.0, -0.5], [-0.5, 2.3, -0.5]])
    with pytest.raises(LimitError) as e:
        check_motion(m)
    assert str(e.value) == ("export: RKneePitch at 0.800 s is 2.3000, outside its range "
                            "-0.1030..2.1201 (NAO H25 V5); --clip clips to the ranges")
    out, clipped = check_motion(m, clip=True)
    assert clipped == 1 and out.values[2, 1] == 2.120051 and m.values[2, 1] == 2.3


def test_speed_violation_names_joint_time_speed_limit():
    m = legs([0, 1200, 1240], [[-0.5, 1.0, -0.5], [-0.5, 1.0, -0.5], [-0.5, 1.316, -0.5]])
    with pytest.raises(LimitError) as e:
        check_motion(m)
    assert str(e.value) == ("export: RKneePitch at 1.240 s moves 7.900 rad/s, above its "
                            "6.40 rad/s limit")
    assert "\n" not in str(e.value)


def test_speed_margin_scales_the_limits():
    m = legs([0, 40], [[-0.5, 1.0, -0.5], [-0.5, 1.24, -0.5]])  # 6.0 rad/s
    check_motion(m)
    with pytest.raises(LimitError, match=r"moves 6\.000 rad/s, above its 5\.76 rad/s limit "
                                         r"\(0\.9 x 6\.40\)$"):
        check_motion(m, speed_margin=0.9)
    for bad in (0.0, 1.5, float("nan")):
        with pytest.raises(InputError, match="speed margin in"):
            check_motion(m, speed_margin=bad)


def test_speeds_are_taken_between_the_keyframes_a_joint_is_given():
    fast = legs([0, 40, 80], [[-0.5, 1.0, -0.5], [-0.5, 1.5, -0.5], [-0.5, 1.5, -0.5]])
    with pytest.raises(LimitError, match="RKneePitch at 0.040 s moves 12.500"):
        check_motion(fast)
    gap = legs([0, 40, 80], [[-0.5, 1.0, -0.5], [-0.5, NAN, -0.5], [-0.5, 1.5, -0.5]])
    check_motion(gap)  # 0.5 rad over 80 ms: 6.25 rad/s


def test_hip_yaw_pitch_must_agree_where_both_are_given():
    joints = ("LHipYawPitch", "RHipYawPitch")
    check_motion(legs([0, 40], [[0.1, 0.1], [0.1, NAN]], joints))
    with pytest.raises(LimitError) as e:
        check_motion(legs([0, 40], [[0.0, 0.0], [0.1, 0.0]], joints))
    assert str(e.value) == ("export: LHipYawPitch 0.1000 and RHipYawPitch 0.0000 differ at "
                            "0.040 s; they are one motor and the robot follows LHipYawPitch")


@pytest.mark.parametrize("name", ["TurnLeft40", "TurnLeft60", "TurnRight40"])
def test_webots_turns_pass_the_checks(name):
    m = read_motion(FIXTURES / f"{name}.motion")
    out, clipped = check_motion(m)
    assert clipped == 0 and out is m


#: The Webots fixtures that exceed a real NAO H25 V5's limits, and the exact errors.
FIXTURE_ERRORS = {
    "HandWave": "export: RShoulderPitch at 1.400 s moves 73.105 rad/s, above its 8.27 rad/s "
                "limit",  # the last pose jumps -1.5 -> 1.42419 rad in 40 ms
    "Shoot": "export: LShoulderPitch at 0.000 s is 2.0940, outside its range -2.0857..2.0857 "
             "(NAO H25 V5) (296 more angles out of range); --clip clips to the ranges",
    "SideStepLeft": "export: LAnkleRoll at 0.960 s is -0.4110, outside its range "
                    "-0.3978..0.7690 (NAO H25 V5) (19 more angles out of range); --clip clips "
                    "to the ranges",
    "SideStepRight": "export: RAnkleRoll at 1.800 s is 0.4060, outside its range "
                     "-0.7690..0.3979 (NAO H25 V5) (19 more angles out of range); --clip clips "
                     "to the ranges",
}


@pytest.mark.parametrize("name", sorted(FIXTURE_ERRORS))
def test_webots_fixtures_beyond_real_limits_give_exact_errors(name):
    with pytest.raises(LimitError) as e:
        check_motion(read_motion(FIXTURES / f"{name}.motion"))
    assert str(e.value) == FIXTURE_ERRORS[name]


def test_clip_makes_the_side_steps_exportable_but_not_the_kick():
    # SideStepLeft: 20 angles out of range + one RAnkleRoll 0.398 within the 1e-4 tolerance
    for name, n in (("SideStepLeft", 21), ("SideStepRight", 20)):
        _, clipped = check_motion(read_motion(FIXTURES / f"{name}.motion"), clip=True)
        assert clipped == n
    with pytest.raises(LimitError) as e:
        check_motion(read_motion(FIXTURES / "Shoot.motion"), clip=True)
    assert str(e.value) == ("export: LElbowRoll at 3.040 s moves 7.300 rad/s, above its "
                            "7.19 rad/s limit (2 more too fast moves)")


# ---- JSON keyframes -------------------------------------------------------------------------

def test_motion_to_json_round_trip(tmp_path):
    m = read_motion(FIXTURES / "TurnLeft60.motion")
    export_motion(m, json_path=tmp_path / "k.json", source="TurnLeft60.motion")
    back, source = read_keyframes(tmp_path / "k.json")
    same(back, m)
    assert source == "TurnLeft60.motion"
    data = json.loads((tmp_path / "k.json").read_text())
    assert data["format"] == "evomotion-keyframes/1"
    assert data["times_s"][:3] == [0.0, 0.04, 0.08]


def test_round_trip_keeps_unset_values_and_a_late_start():
    m = legs([120, 160, 1240], [[-0.5, 1.0, NAN], [NAN, 1.1, -0.5], [-0.4, 1.2 + 1e-13, -0.45]])
    back, _ = parse_keyframes(keyframes_json(m, "hand-made"))
    same(back, m)


@pytest.mark.parametrize("text,msg", [
    ("{", "k.json:1: column 2: invalid JSON"),
    ("[]", "expected a JSON object"),
    ('{"format": "other/1"}', 'expected "format": "evomotion-keyframes/1"'),
    ('{"format": "evomotion-keyframes/1", "angles": {}}', "unexpected key 'angles'"),
    ('{"format": "evomotion-keyframes/1", "joints": ["Tail"]}', "unknown joint 'Tail'"),
    ('{"format": "evomotion-keyframes/1", "joints": ["HeadYaw", "HeadYaw"]}', "each joint"),
    ('{"format": "evomotion-keyframes/1", "joints": ["HeadYaw"], "times_s": [0, NaN]}',
     "expected finite numbers, got NaN"),
    ('{"format": "evomotion-keyframes/1", "joints": ["HeadYaw"], "times_s": [0, true]}',
     "list of finite numbers"),
    ('{"format": "evomotion-keyframes/1", "joints": ["HeadYaw"], "times_s": [0, 1e999]}',
     "expected finite numbers, got 1e999"),
    ('{"format": "evomotion-keyframes/1", "joints": ["HeadYaw"], "times_s": [0, 1e308]}',
     "whole milliseconds from 0 to 600 s"),
    ('{"format": "evomotion-keyframes/1", "joints": ["HeadYaw"], "times_s": [0, 0.0405]}',
     "whole milliseconds"),
    ('{"format": "evomotion-keyframes/1", "joints": ["HeadYaw"], "times_s": [0.1, 0.1]}',
     "strictly increasing"),
    ('{"format": "evomotion-keyframes/1", "joints": ["HeadYaw"], "times_s": [0], '
     '"angles_rad": {}}', 'one list per joint'),
    ('{"format": "evomotion-keyframes/1", "joints": ["HeadYaw"], "times_s": [0, 1], '
     '"angles_rad": {"HeadYaw": [0]}}', "expected 2 angles for HeadYaw"),
    ('{"format": "evomotion-keyframes/1", "joints": ["HeadYaw"], "times_s": [0], '
     '"angles_rad": {"HeadYaw": ["0"]}}', "finite numbers or null as angles of HeadYaw"),
    ('{"format": "evomotion-keyframes/1", "joints": ["HeadYaw"], "times_s": [0], '
     '"angles_rad": {"HeadYaw": [0]}, "source": 3}', '"source" to be a string'),
    ("[" * 100000, "k.json: expected JSON nested at most 4 deep"),
])
def test_bad_keyframe_files_are_one_line_errors(text, msg):
    with pytest.raises(FileFormatError) as e:
        parse_keyframes(text, "k.json")
    assert msg in str(e.value) and "\n" not in str(e.value), str(e.value)


def test_keyframe_reader_rejects_non_utf8_and_missing_files(tmp_path):
    (tmp_path / "k.json").write_bytes(b'{"format": "\xff"}')
    with pytest.raises(FileFormatError, match="expected UTF-8 text"):
        read_keyframes(tmp_path / "k.json")
    with pytest.raises(FileFormatError, match="expected an existing keyframe file"):
        read_keyframes(tmp_path / "none.json")


# ---- NAOqi script ----------------------------------------------------------------------------

def run_script(script: Path, tmp_path: Path, *args: str) -> list:
    fake = tmp_path / "fake"
    fake.mkdir(exist_ok=True)
    (fake / "naoqi.py").write_text(FAKE_NAOQI)
    log = tmp_path / "calls.json"
    log.unlink(missing_ok=True)
    env = {**os.environ, "PYTHONPATH": str(fake), "FAKE_NAOQI_LOG": str(log)}
    r = subprocess.run([sys.executable, str(script), *args], capture_output=True, text=True,
                       env=env, timeout=60)
    assert r.returncode == 0, r.stderr
    return json.loads(log.read_text())


def test_naoqi_script_compiles_and_names_joints_and_times(tmp_path):
    m = read_motion(FIXTURES / "TurnLeft60.motion")
    text = naoqi_script(m, "TurnLeft60.motion")
    compile(text, "TurnLeft60_naoqi.py", "exec")
    for name in m.joints:
        assert f'"{name}"' in text
    assert "4.52]" in text and "[0.04, 0.08," in text
    assert 'naoqi.ALProxy("ALMotion", args.ip, args.port)' in text
    assert text.count("angleInterpolation(") == 1


def test_naoqi_script_makes_one_angle_interpolation_call(tmp_path):
    m = read_motion(FIXTURES / "TurnLeft60.motion")
    export_motion(m, naoqi=tmp_path / "t.py")
    calls = run_script(tmp_path / "t.py", tmp_path)
    assert [c[0] for c in calls] == ["ALProxy", "wakeUp", "angleInterpolationWithSpeed",
                                     "angleInterpolation"]
    assert calls[0][1] == ["ALMotion", "127.0.0.1", 9559]
    names, angles, times, absolute = calls[3][1]
    assert names == list(m.joints) and absolute is True
    t = (m.times_ms[1:] / 1000.0).tolist()
    for j, name in enumerate(m.joints):
        assert angles[j] == m.column(name)[1:].tolist() and times[j] == t
    assert calls[2][1] == [list(m.joints), m.values[0].tolist(), 0.2]


def test_naoqi_script_skips_unset_values_and_rests_only_when_asked(tmp_path):
    m = legs([100, 140, 180, 220], [[-0.5, 1.0, -0.5], [NAN, 1.05, NAN], [-0.52, NAN, NAN],
                                    [-0.5, 1.0, NAN]])
    m = Motion(m.joints + ("HeadYaw",), m.times_ms,
               np.column_stack([m.values, [0.1, NAN, NAN, NAN]]))
    export_motion(m, naoqi=tmp_path / "m.py")
    calls = run_script(tmp_path / "m.py", tmp_path, "--ip", "10.0.0.7", "--port", "9560",
                       "--rest", "--speed", "0.1")
    assert [c[0] for c in calls] == ["ALProxy", "wakeUp", "angleInterpolationWithSpeed",
                                     "angleInterpolation", "rest"]
    assert calls[0][1] == ["ALMotion", "10.0.0.7", 9560]
    assert calls[2][1] == [["RHipPitch", "RKneePitch", "RAnklePitch", "HeadYaw"],
                           [-0.5, 1.0, -0.5, 0.1], 0.1]
    names, angles, times, absolute = calls[3][1]
    assert names == ["RHipPitch", "RKneePitch"]  # RAnklePitch and HeadYaw: given only first
    assert angles == [[-0.52, -0.5], [1.05, 1.0]]
    assert times == [[0.08, 0.12], [0.04, 0.12]]
    assert naoqi_plan(m)[2:] == (names, angles, times)


# ---- CLI and the study hook --------------------------------------------------------------

def cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "evomotion.cli", "export", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd, timeout=120)


def test_cli_writes_what_it_says(tmp_path):
    r = cli(FIXTURES / "SideStepLeft.motion", "--naoqi", tmp_path / "s.py", "--json",
            tmp_path / "s.json", "--clip", "--speed-margin", "0.9", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines() == [
        "clipped 21 angles to the NAO H25 V5 joint ranges",
        f"wrote {tmp_path / 's.py'} (NAOqi script; 20 joints, 124 keyframes, 4.920 s)",
        f"wrote {tmp_path / 's.json'} (keyframes; 20 joints, 124 keyframes, 4.920 s)"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.json", "s.py"]


@pytest.mark.parametrize("args,msg", [
    ([], "export: expected at least one output (--naoqi OUT.py, --json OUT.json)"),
    (["--json", "{tmp}/k.json"], FIXTURE_ERRORS["Shoot"]),
    (["--json", "{tmp}/k.json", "--speed-margin", "0"], "export: expected a speed margin in"),
    (["--naoqi", "{tmp}/no/such/dir/k.py"], "does not exist (make it first)"),
])
def test_cli_errors_are_one_line_exit_2(tmp_path, args, msg):
    r = cli(FIXTURES / "Shoot.motion", *[a.format(tmp=tmp_path) for a in args], cwd=tmp_path)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ") and msg in lines[0], r.stderr
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_cli_missing_motion_is_one_line_error(tmp_path):
    r = cli(tmp_path / "none.motion", "--json", tmp_path / "k.json")
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "none.motion" in r.stderr


def test_study_hook_writes_exports_or_logs_why_not(tmp_path, monkeypatch):
    from evomotion.run.config import resolve_config
    from evomotion.run.context import RunContext
    from evomotion.studies import get_study
    from evomotion.studies.humanoid_step import artifacts

    study = get_study("humanoid-step")
    cfg = resolve_config(study, None, ["problem.intervals=4", "problem.motion_s=0.4",
                                       "problem.threads=1"])
    problem = study.make_problem(cfg.problem)
    genome = 0.5 * (problem.genome.lower + problem.genome.upper)
    logged: list[str] = []
    ctx = RunContext("humanoid-step", tmp_path, cfg, problem, best_genome=genome,
                     log=logged.append)
    assert artifacts.write_exports(ctx)
    back, source = read_keyframes(tmp_path / "best_keyframes.json")
    same(back, artifacts.genome_motion(problem, genome))
    assert source == "best.motion"
    compile((tmp_path / "best_naoqi.py").read_text(), "best_naoqi.py", "exec")

    too_fast = legs([0, 40], [[-0.5, 1.0, -0.5], [-0.5, 2.0, -0.5]])
    monkeypatch.setattr(artifacts, "genome_motion", lambda p, g: too_fast)
    assert not artifacts.write_exports(ctx)
    assert logged[-1] == ("best_naoqi.py and best_keyframes.json not written: export: "
                          "RKneePitch at 0.040 s moves 25.000 rad/s, above its 6.40 rad/s "
                          "limit")
    assert not (tmp_path / "best_naoqi.py").exists()  # the earlier best's exports are gone
    assert not (tmp_path / "best_keyframes.json").exists()
