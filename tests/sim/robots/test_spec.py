"""Robot specs (``sim/robot``): bundled robots build and stand; every mistake in a spec is one
``FILE:LINE`` error; the reader never fails with anything but :class:`InputError`."""

from __future__ import annotations

import textwrap
from pathlib import Path

import mujoco
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from evomotion.errors import InputError
from evomotion.sim.robots import build_robot, bundled_robots, load_robot, read_spec, spec_path
from evomotion.sim.robots.spec import key_lines

NAO_MJCF = "evomotion:sim/robots/nao/nao_h25.xml"
HAS_DM = __import__("importlib").util.find_spec("dm_control") is not None


def _stands(robot, seconds: float = 3.0) -> tuple[float, float, float]:
    """(lowest torso height, largest tilt (rad), horizontal drift (m)) holding the pose."""
    from mujoco import rollout

    m = robot.model
    n = int(seconds / m.opt.timestep)
    states, _ = rollout.rollout(m, mujoco.MjData(m), robot.state0[None],
                                np.tile(robot.pose, (1, n, 1)))
    q = states[0, :, 1:8]
    tilt = np.arccos(np.clip(1 - 2 * (q[:, 4] ** 2 + q[:, 5] ** 2), -1, 1))
    return float(q[:, 2].min()), float(tilt.max()), float(np.linalg.norm(q[-1, :2] - q[0, :2]))


@pytest.mark.parametrize("name", bundled_robots())
def test_bundled_robot_builds_and_stands(name):
    if name.startswith("dm-") and not HAS_DM:
        pytest.skip("dm_control is not installed")
    robot = load_robot(name)
    assert robot.model.nu == len(robot.joints) and robot.evolved
    assert np.all(robot.lower < robot.upper)
    assert (robot.pose[robot.columns] >= robot.lower - 1e-9).all()
    assert robot.state0.shape == (mujoco.mj_stateSize(robot.model,
                                                      mujoco.mjtState.mjSTATE_FULLPHYSICS),)
    for foot in robot.feet:
        assert robot.sensor(f"{foot}_pos").stop - robot.sensor(f"{foot}_pos").start == 3
        robot.sensor(f"{foot}_floor")
    low, tilt, drift = _stands(robot)
    assert low > robot.fall_height_m and tilt < 0.3 and drift < 0.05, (low, tilt, drift)


def test_nao_spec_is_the_nao():
    """The NAO's spec gives its studies' model, initial states, bounds and fall thresholds bit
    for bit (the default robot of the humanoid studies is this spec)."""
    from evomotion.sim.robots import nao
    from evomotion.studies.humanoid_step.problem import servo_bounds

    robot = load_robot("nao")
    assert robot.joints == tuple(nao.JOINTS)
    np.testing.assert_array_equal(robot.pose, nao.pose_vector())
    np.testing.assert_array_equal(robot.state0, nao.initial_state(nao.load_model()))
    pose = nao.pose_vector() + 0.1
    np.testing.assert_array_equal(robot.state_at(pose), nao.initial_state(nao.load_model(), pose))
    assert (robot.fall_height_m, robot.fall_tilt_rad) == (nao.FALL_HEIGHT_M, nao.FALL_TILT_RAD)
    lo, hi = servo_bounds(nao.load_model())  # the paper's Table 1 within the model's ranges
    assert robot.evolved == nao.LEG_SERVOS
    np.testing.assert_array_equal(robot.lower, lo)
    np.testing.assert_array_equal(robot.upper, hi)
    assert robot.sole_site("left") == "l_sole_site"


@pytest.mark.skipif(not HAS_DM, reason="dm_control is not installed")
def test_motors_become_position_servos():
    robot = load_robot("dm-humanoid")
    m = robot.model
    assert (m.actuator_gaintype == mujoco.mjtGain.mjGAIN_FIXED).all()
    assert (m.actuator_biastype == mujoco.mjtBias.mjBIAS_AFFINE).all()  # position servos
    assert np.allclose(m.actuator_gainprm[:, 0], 1000.0)
    hip = m.actuator("right_hip_y").id
    assert np.allclose(m.actuator_forcerange[hip], [-120, 120])  # the motor's gear 120
    assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    assert robot.xml.startswith("<mujoco")


def _spec(tmp_path: Path, body: str, name: str = "r.toml") -> Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(body).lstrip())
    return path


GOOD = f"""
[robot]
name = "nao-copy"
mjcf = "{NAO_MJCF}"
torso = "torso"

[feet]
left = "LFoot"
right = "RFoot"

[fall]
height_m = 0.2

[evolve]
LKneePitch = [0.0, 1.5]
"""


@pytest.mark.parametrize("change,line,message", [
    (("[fall]", "[falls]"), 10, "unknown section [falls]"),
    (('height_m = 0.2', 'height = 0.2'), 11, "[fall] unknown key 'height'"),
    (('LKneePitch = [0.0, 1.5]', 'LKnee = [0.0, 1.5]'), 14, "unknown joint 'LKnee'"),
    (('LKneePitch = [0.0, 1.5]', 'LKneePitch = [0.0, 3.5]'), 14,
     "outside the model's joint range"),
    (('LKneePitch = [0.0, 1.5]', 'LKneePitch = [1.5, 0.0]'), 14, "expected lo < hi"),
    (('left = "LFoot"', 'left = "LHip"'), 7, "has no collision geoms (no sole geoms)"),
    (('left = "LFoot"', 'left = "LToe"'), 7, "no body 'LToe'"),
    (('torso = "torso"', 'torso = "LFoot"'), 4, "must carry the model's first joint"),
    (('height_m = 0.2', 'height_m = -1'), 11, "expected a number in (0, 10] m, got -1"),
    ((f'mjcf = "{NAO_MJCF}"', 'mjcf = "missing.xml"'), 3, "no such MJCF file"),
])
def test_spec_mistakes_name_file_line_and_expectation(tmp_path, change, line, message):
    path = _spec(tmp_path, GOOD.replace(*change))
    with pytest.raises(InputError) as e:
        build_robot(read_spec(path))
    text = str(e.value)
    assert text.startswith(f"{path}:{line}: "), text
    assert message in text and "\n" not in text


@pytest.mark.parametrize("soles,line,message", [
    ('left = "l_sole_site"\nright = "nope"', 12, "[soles] right: no site 'nope' in the MJCF"),
    ('left = "r_sole_site"\nright = "r_sole_site"', 11,
     "site 'r_sole_site' is not on the foot body 'LFoot'"),
    ('left = "l_sole_site"', 10, "[soles]: expected a site for every foot, missing 'right'"),
    ('middle = "l_sole_site"', 11, "[soles] middle: not a foot of [feet]"),
])
def test_sole_site_mistakes(tmp_path, soles, line, message):
    text = GOOD.replace("[fall]", f"[soles]\n{soles}\n\n[fall]")
    path = _spec(tmp_path, text)
    with pytest.raises(InputError) as e:
        build_robot(read_spec(path))
    assert str(e.value).startswith(f"{path}:{line}: ") and message in str(e.value), e.value


def test_good_spec_builds(tmp_path):
    robot = build_robot(read_spec(_spec(tmp_path, GOOD)))
    assert robot.evolved == ("LKneePitch",) and robot.name == "nao-copy"


def test_motors_without_servo_section_are_refused(tmp_path):
    mjcf = tmp_path / "motor.xml"
    mjcf.write_text("""<mujoco><worldbody><geom name="floor" type="plane" size="5 5 .1"/>
      <body name="torso" pos="0 0 .5"><freejoint/><geom type="box" size=".1 .1 .1"/>
        <body name="foot" pos="0 0 -.2"><joint name="j" type="hinge" range="-60 60"/>
          <geom type="box" size=".05 .05 .02"/></body></body></worldbody>
      <actuator><motor joint="j" gear="10"/></actuator></mujoco>""")
    path = _spec(tmp_path, """
        [robot]
        name = "m"
        mjcf = "motor.xml"
        torso = "torso"
        [feet]
        only = "foot"
        [fall]
        height_m = 0.1
        """)
    with pytest.raises(InputError, match=r"r.toml:3: \[robot\] mjcf: the MJCF drives 1 joints "
                                         r"with motors .* add a \[servo\] section"):
        build_robot(read_spec(path))
    path.write_text(path.read_text() + "[servo]\nkp = 50.0\nkv = 1.0\n[evolve]\nj = [-0.5, 0.5]\n")
    robot = build_robot(read_spec(path))
    assert robot.model.actuator_forcerange[0, 1] == 10.0 and robot.joints == ("j",)


def test_unknown_robot_name_lists_the_bundled_ones():
    with pytest.raises(InputError, match="unknown robot 'r2d2'; bundled: .*nao"):
        spec_path("r2d2")


def test_key_lines():
    lines = key_lines("[a]\nx = 1\n\n[b]\n\"y\" = 2\n")
    assert lines == {("a", ""): 1, ("a", "x"): 2, ("b", ""): 4, ("b", "y"): 5}


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                 HealthCheck.function_scoped_fixture])
@given(st.text(max_size=300) | st.sampled_from([GOOD]).map(
    lambda s: s.replace("0.2", "x")) | st.binary(max_size=200).map(
    lambda b: b.decode("latin-1")))
def test_reader_fuzz_only_input_errors(tmp_path, text):
    path = tmp_path / "fuzz.toml"
    path.write_text(text, encoding="utf-8", errors="surrogateescape")
    try:
        build_robot(read_spec(path))
    except InputError as e:
        assert "\n" not in str(e)


def test_a_bundled_name_wins_over_a_folder_of_that_name(tmp_path, monkeypatch):
    """``evomotion run humanoid-step --out nao`` makes ./nao: the NAO is still the bundled
    spec, and a path to a spec still works."""
    from evomotion.sim.robots import ROBOTS_DIR, spec_path

    monkeypatch.chdir(tmp_path)
    (tmp_path / "nao").mkdir()
    (tmp_path / "op3").write_text("not a spec")
    assert spec_path("nao") == ROBOTS_DIR / "nao" / "nao.toml"
    assert spec_path("op3") == ROBOTS_DIR / "op3" / "op3.toml"
    assert load_robot("nao").name == "nao"
    mine = tmp_path / "sub" / "nao.toml"
    mine.parent.mkdir()
    mine.write_text((spec_path("nao")).read_text())
    assert spec_path("sub/nao.toml") == Path("sub/nao.toml")
