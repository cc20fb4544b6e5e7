
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.errors import FileFormatError
from evomotion.sim.motion import (
    Motion,
    format_motion,
    format_time_ms,
    parse_time_ms,
    read_motion,
    write_motion,
)
from fixture_files import WEBOTS_MOTIONS

FIXTURES = WEBOTS_MOTIONS
LEGS = ("LHipPitch", "LKneePitch", "RHipPitch")


def _write(tmp_path, text, name="m.motion"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_header_on_first_line_variant(tmp_path):
    p = _write(tmp_path, "#WEBOTS_MOTION,V1.0,LHipPitch,RHipPitch\n"
                         "00:00:000,Pose1,0.1,0.2\n00:01:040,Pose2,-0.5,*\n")
    m = read_motion(p)
    assert m.joints == ("LHipPitch", "RHipPitch")
    assert m.times_ms.tolist() == [0, 1040]
    assert m.pose_names == ["Pose1", "Pose2"]
    assert m.values[0].tolist() == [0.1, 0.2]
    assert m.values[1, 0] == -0.5 and np.isnan(m.values[1, 1])


def test_header_on_second_line_variant_and_crlf(tmp_path):
    p = _write(tmp_path, "#WEBOTS_MOTION,V1.0\r\nLHipPitch,RHipPitch\r\n00:00:040,A,1,2\r\n")
    m = read_motion(p)
    assert m.joints == ("LHipPitch", "RHipPitch")
    assert m.times_ms.tolist() == [40]


def test_empty_line_ends_file(tmp_path):
    p = _write(tmp_path, "#WEBOTS_MOTION,V1.0,LHipPitch\n00:00:000,P,1\n\ngarbage\n")
    assert len(read_motion(p).times_ms) == 1


@pytest.mark.parametrize("name,variant_first_line", [
    ("TurnLeft60.motion", True), ("TurnLeft40.motion", False), ("HandWave.motion", False),
    ("SideStepLeft.motion", False), ("Shoot.motion", False),
])
def test_webots_fixtures_parse(name, variant_first_line):
    text = (FIXTURES / name).read_text()
    assert (text.splitlines()[0].count(",") > 1) == variant_first_line
    m = read_motion(FIXTURES / name)
    assert np.all(np.diff(m.times_ms) > 0)
    assert np.all(np.isfinite(m.values))
    assert np.all(np.diff(m.times_ms) == 40)


def test_turnleft60_matches_reference_facts():
    m = read_motion(FIXTURES / "TurnLeft60.motion")
    assert len(m.times_ms) == 114 and m.duration_s == pytest.approx(4.52)
    assert m.values[0, m.joints.index("LHipPitch")] == -0.525


@pytest.mark.parametrize("text,line,fragment", [
    ("#WEBOTS_MOTION,V1.0,LHipPitch\n00:00:000,P,1\n00:0x:040,P,2\n", 3, "bad time stamp"),
    ("#WEBOTS_MOTION,V1.0,LHipPitch\n00:00:000,P,1\n00:00:000,P,2\n", 3, "increasing"),
    ("#WEBOTS_MOTION,V1.0,LHipPitch,RHipPitch\n00:00:000,P,1\n", 2, "expected 2 values, got 1"),
    ("#WEBOTS_MOTION,V1.0,LHipPitch\n00:00:000,P,1,2\n", 2, "expected 1 values, got 2"),
    ("#WEBOTS_MOTION,V1.0\nLHipPitch,LTail\n00:00:000,P,1,2\n", 2, "unknown joint 'LTail'"),
    ("#WEBOTS_MOTION,V1.0,LHipPitch\n00:00:000,P,abc\n", 2, "bad value"),
    ("#WEBOTS_MOTION,V2.0,LHipPitch\n00:00:000,P,1\n", 1, "header"),
    ("#WEBOTS_MOTION,V1.0,LHipPitch\n", 2, "at least one pose"),
])
def test_malformed_files_name_file_and_line(tmp_path, text, line, fragment):
    p = _write(tmp_path, text)
    with pytest.raises(FileFormatError) as err:
        read_motion(p)
    assert err.value.line == line
    assert fragment in str(err.value)
    assert str(err.value).startswith(f"{p}:{line}: ")
    assert "\n" not in str(err.value)


def test_time_stamps():
    assert parse_time_ms("00:01:040") == 1040
    assert parse_time_ms("02:03:004") == 123004
    assert parse_time_ms("1:500") == 1500 and parse_time_ms("250") == 250
    assert parse_time_ms("1:2:3:4") is None and parse_time_ms("1.5") is None
    assert format_time_ms(123004) == "02:03:004"


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(1, 200_000), min_size=1, max_size=20, unique=True),
       st.integers(0, 2**31), st.booleans())
def test_round_trip_is_exact(tmp_path_factory, times, seed, first_line):
    rng = np.random.default_rng(seed)
    times = np.sort(np.array(times))
    values = rng.uniform(-2, 2, size=(len(times), len(LEGS)))
    values[rng.random(values.shape) < 0.1] = np.nan
    m = Motion(LEGS, times, values)
    p = tmp_path_factory.mktemp("rt") / "x.motion"
    write_motion(p, m, header_on_first_line=first_line)
    back = read_motion(p)
    assert back.joints == m.joints and back.pose_names == m.pose_names
    np.testing.assert_array_equal(back.times_ms, m.times_ms)
    np.testing.assert_array_equal(back.values, m.values)  # NaN == NaN for assert_array_equal
    assert format_motion(back, first_line) == p.read_text()


def test_fixture_round_trip(tmp_path):
    m = read_motion(FIXTURES / "SideStepLeft.motion")
    write_motion(tmp_path / "s.motion", m)
    back = read_motion(tmp_path / "s.motion")
    np.testing.assert_array_equal(back.values, m.values)
    assert back.pose_names == m.pose_names


def test_shipped_shoot_is_the_webots_fixture():
    from importlib import resources

    from evomotion.sim.robots.nao.webots_motions import SHIPPED_MOTIONS, shipped_motion

    assert "Shoot" in SHIPPED_MOTIONS
    shipped = resources.files("evomotion.sim.robots.nao").joinpath("motions", "Shoot.motion")
    assert shipped.read_bytes() == (FIXTURES / "Shoot.motion").read_bytes()
    assert "Cyberbotics" in resources.files("evomotion.sim.robots.nao").joinpath(
        "motions", "NOTICE.txt").read_text()
    m, ref = shipped_motion("Shoot"), read_motion(FIXTURES / "Shoot.motion")
    assert m.joints == ref.joints and m.pose_names == ref.pose_names
    np.testing.assert_array_equal(m.values, ref.values)
    with pytest.raises(ValueError, match="no shipped motion"):
        shipped_motion("Moonwalk")
