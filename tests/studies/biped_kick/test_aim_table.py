"""The kick's aim table: measured, it is what the kick does at its grid points; inverted, it
picks the commanded aim whose predicted direction is the target (a synthetic table: exactly),
within the limits, never one predicted to go short, the left foot as the right one mirrored;
on the real kick it brings an offset ball's kick nearer its aim than following the ball alone;
its file round-trips and any bad file is one line."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.errors import InputError
from evomotion.studies.biped_kick import aim_table
from evomotion.studies.biped_kick.experiment import perturbed_kicks
from evomotion.studies.biped_kick.play import read_kick
from evomotion.studies.biped_kick.problem import KickConfig, KickProblem


@pytest.fixture(scope="module")
def kick():
    genome, _ = read_kick(None)
    return KickProblem(KickConfig(nthread=2)), genome


def synthetic(slope_deg_per_m: float = 500.0) -> aim_table.AimTable:
    """A table whose ball goes ``aim + slope * dy``, 2 m."""
    aims, dx, dy = np.arange(-40.0, 40.1, 2.5), np.array([-0.02, 0.02]), np.linspace(-0.06,
                                                                                    0.06, 25)
    a, _, y = np.meshgrid(aims, dx, dy, indexing="ij")
    return aim_table.AimTable(aims, dx, dy, a + slope_deg_per_m * y, np.full(a.shape, 2.0),
                              KickConfig().adapt_max_stretch, KickConfig().adapt_foot_roll_rad)


def test_command_inverts_the_table(kick):
    p, g = kick
    table = synthetic()
    want = p.wanted_ball_xy(g[None], np.radians([-10.0]))[0]
    balls = want + np.array([[0.0, 0.0], [0.005, -0.01], [0.0, 0.012]])
    cmd = aim_table.command(table, p, g, -10.0, balls)
    assert cmd[0] == -10.0  # the ball in its place: the aim itself
    rel = balls - p.wanted_ball_xy(np.repeat(g[None], 3, 0), np.radians(cmd))
    angle, _ = table.interpolate(np.column_stack([cmd, rel]))
    assert np.all(np.abs(angle - -10.0) <= aim_table.TOLERANCE_DEG + 0.1)  # 0.25 deg steps
    assert cmd[1] > -8.0 and cmd[2] < -12.0  # a ball to the right: aimed further left
    # the left foot: the right one mirrored
    mirrored = balls * [1.0, -1.0]
    assert np.array_equal(aim_table.command(table, p, g, 10.0, mirrored, left_foot=True), -cmd)
    # commands predicted to go short are never taken; none left: the aim itself
    short = dataclasses.replace(table, distance_m=np.where(
        table.aims_deg[:, None, None] > -8.0, 0.5, table.distance_m))
    assert aim_table.command(short, p, g, -10.0, balls[1:2])[0] <= -8.0
    assert aim_table.command(table, p, g, -10.0, want[None] + [0.5, 0.0])[0] == -10.0


def test_commands_stay_within_the_limits(kick):
    p, g = kick
    cands = np.arange(-40.0, 40.01, 0.25)
    evolved = KickProblem(dataclasses.replace(p.cfg, adapt_max_stretch=1.0))
    ok1 = aim_table.within_limits(evolved, g, cands, False)
    assert ok1.any() and not ok1.all()  # the shipped kick's own timing: about -34 ... +31 deg
    assert cands[ok1].max() < 32.0 and cands[ok1].min() > -35.0
    ok = aim_table.within_limits(p, g, cands, False)  # its swing up to 1.25x longer: more
    assert np.all(ok[ok1]) and ok[cands == 36.0].all() and ok[cands == -38.0].all()
    # a table where the ball goes where the command says: at +36 deg the command is 36 (slowed
    # down); at the evolved timing the nearest within its limits
    table = synthetic(slope_deg_per_m=0.0)
    want = p.wanted_ball_xy(g[None], np.radians([36.0]))[0]
    assert aim_table.command(table, p, g, 36.0, want[None])[0] == 36.0
    cmd1 = aim_table.command(dataclasses.replace(table, max_stretch=1.0), evolved, g, 36.0,
                             want[None])[0]
    assert cmd1 == cands[ok1].max() < 32.0
    with pytest.raises(InputError, match="adapt_max_stretch = 1, the kick follows the ball "
                                         "with 1.25") as e:  # a table of another timing
        aim_table.command(dataclasses.replace(table, max_stretch=1.0), p, g, -30.0, want[None])
    assert "\n" not in str(e.value)
    with pytest.raises(InputError, match="adapt_foot_roll_rad = 0, the kick follows the ball "
                                         "with 0.1") as e:  # a table of a level sole
        aim_table.command(dataclasses.replace(table, foot_roll_rad=0.0), p, g, -30.0,
                          want[None])
    assert "\n" not in str(e.value)


def test_the_table_calibrates_the_real_kick(kick):
    """With the sole kept level (``adapt_foot_roll_rad`` 0) the swing follows an outboard ball
    only in part: the table's command makes up for the rest."""
    p, g = kick
    p = KickProblem(dataclasses.replace(p.cfg, adapt_foot_roll_rad=0.0))
    table = aim_table.measure(p, g, np.arange(-20.0, -7.4, 2.5), np.array([-0.005, 0.005]),
                              np.linspace(-0.03, 0.0, 7))
    # a grid point is what the kick does there
    k = perturbed_kicks(p, g, np.array([[0.005, -0.02]]), -15.0, adapt=True)
    assert abs(k["angle_error_deg"][0] - 15.0 - table.angle_deg[2, 1, 2]) < 1e-9
    # balls 1-1.5 cm to the right of their place (outboard: the swing cannot follow them all
    # the way): nearer the aim than following them alone, by a command further right
    off = np.array([[0.0, -0.015], [0.0, -0.01], [0.003, -0.012]])
    alone = perturbed_kicks(p, g, off, -10.0, adapt=True)
    calibrated = perturbed_kicks(p, g, off, -10.0, adapt=True, table=table)
    assert np.all(calibrated["command_deg"] < -12.0)
    err, err0 = np.abs(calibrated["angle_error_deg"]), np.abs(alone["angle_error_deg"])
    assert np.all(err < err0 - 3.0) and np.all(err < 9.0) and not calibrated["fell"].any()


def test_the_file_round_trips_and_bad_files_are_one_line(tmp_path):
    table = synthetic()
    f = aim_table.write(tmp_path / "t.json", table, "shipped")
    back = aim_table.read(f)
    for field in dataclasses.fields(table):
        assert np.array_equal(getattr(back, field.name), getattr(table, field.name))
    rec = json.loads(f.read_text())
    for change, msg in (({"format": "x"}, "expected a kick aim table"),
                        ({"dx_m": [0.0, 0.0]}, "increasing"),
                        ({"dy_m": [0.0]}, "at least 2"),
                        ({"angle_deg": [[[1.0]]]}, r"grid \(aims x dx x dy\)"),
                        ({"distance_m": "x"}, "nested list of numbers"),
                        ({"aims_deg": [0.0, None]}, "all finite"),
                        ({"adapt_max_stretch": 0.5}, "adapt_max_stretch"),
                        ({"aims_deg": [-1e6, 1e6]}, "within"),
                        ({"dy_m": list(np.linspace(-0.1, 0.1, 2000))}, "at most 1000"),
                        ({"adapt_max_stretch": "1"}, "adapt_max_stretch"),
                        ({"adapt_foot_roll_rad": 0.9}, "adapt_foot_roll_rad"),
                        ({"adapt_foot_roll_rad": True}, "adapt_foot_roll_rad")):
        bad = tmp_path / "bad.json"
        bad.write_text(json.dumps({**rec, **change}))
        with pytest.raises(InputError, match=msg) as e:
            aim_table.read(bad)
        assert str(bad) in str(e.value) and "\n" not in str(e.value)
    del rec["adapt_max_stretch"]  # a file from before the keys: the evolved timing, level sole
    del rec["adapt_foot_roll_rad"]
    f.write_text(json.dumps(rec))
    old = aim_table.read(f)
    assert old.max_stretch == 1.0 and table.max_stretch == 1.25
    assert old.foot_roll_rad == 0.0 and table.foot_roll_rad == 0.1
    # read_or_measure reads an existing file, refusing one of another following in one line
    p = KickProblem(KickConfig(nthread=1))
    f2 = aim_table.write(tmp_path / "t2.json", table)
    back = aim_table.read_or_measure(f2, p, read_kick(None)[0])
    assert np.array_equal(back.angle_deg, table.angle_deg)
    with pytest.raises(InputError, match=r"--table .*adapt_max_stretch = 1, the kick") as e:
        aim_table.read_or_measure(f, p, read_kick(None)[0])
    assert "\n" not in str(e.value)


JSONISH = st.recursive(st.none() | st.booleans() | st.floats(allow_nan=False) | st.text(max_size=5),
                       lambda c: st.lists(c, max_size=4) | st.dictionaries(st.text(max_size=5), c,
                                                                           max_size=4),
                       max_leaves=30)


@settings(max_examples=150, deadline=None)
@given(data=st.binary(max_size=200) | st.builds(
    lambda d: json.dumps({"format": aim_table.FORMAT, **d}).encode(),
    st.dictionaries(st.sampled_from(["aims_deg", "dx_m", "dy_m", "angle_deg", "distance_m",
                                     "adapt_max_stretch", "adapt_foot_roll_rad"]),
                    JSONISH, max_size=5)))
def test_any_file_reads_or_is_one_line(tmp_path_factory, data):
    f = tmp_path_factory.mktemp("fuzz") / "t.json"
    f.write_bytes(data)
    try:
        aim_table.read(f)
    except InputError as e:
        assert "\n" not in str(e)


def _calibrate(*args, cwd):
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "evomotion.cli", "biped-kick", "calibrate",
                           *args], capture_output=True, text=True, cwd=cwd, timeout=300)


def test_calibrate_writes_the_table(tmp_path):
    r = _calibrate("--out", "t.json", "--aim-step", "40", "--dy-step", "0.06", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    table = aim_table.read(tmp_path / "t.json")
    assert np.array_equal(table.aims_deg, [-40.0, 0.0, 40.0]) and table.angle_deg.shape == (
        3, len(aim_table.DX_M), 3)
    assert abs(table.angle_deg[1, 2, 1]) < 2.0 and table.distance_m[1, 2, 1] > 2.0  # straight


@pytest.mark.parametrize("args,msg", [
    (["--out", "t.txt"], "expected a .json path"),
    (["--out", "nofolder/t.json"], "does not exist"),
    (["--out", "t.json", "--aim-step", "0"], "--aim-step"),
    (["--out", "t.json", "--dy-step", "nan"], "--dy-step"),
    (["--out", "t.json", "--kick", "missing"], "no such file"),
])
def test_calibrate_bad_input_is_one_line(tmp_path, args, msg):
    r = _calibrate(*args, cwd=tmp_path)
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode == 2 and len(lines) == 1 and msg in lines[0], r.stderr
    assert not (tmp_path / "t.json").exists()
